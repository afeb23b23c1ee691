// Motion CSV for the offline commands: see motion_input.hpp.
#include "motion_input.hpp"
#include "config_key_options.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "toposlam/core/csv.hpp"

namespace toposlam::cli {
namespace {

double number(const std::string& field, const std::string& where, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(field.c_str(), &end);
  if (field.empty() || end == field.c_str() || *end != '\0' || !std::isfinite(v))
    throw std::runtime_error(where + ": " + what + " '" + field + "' is not a finite number");
  return v;
}

}  // namespace

std::vector<MotionCsvSample> readMotionCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("--motion: cannot read '" + path + "'");
  CsvReader reader(in);
  CsvRecord record;
  if (!reader.next(record)) throw std::runtime_error("--motion: '" + path + "' is empty");
  const std::string& header = record.text;
  const bool with_turn = header == "time_s,distance_m,speed_mps,turn_rate_rps";
  if (header != "time_s,distance_m,speed_mps" && !with_turn)
    throw std::runtime_error("--motion: " + path + ":" + std::to_string(record.line) +
                             ": header must be 'time_s,distance_m,speed_mps' (and optionally "
                             "',turn_rate_rps'), got '" + header + "'");
  const std::string fields = with_turn ? "4 fields (time_s,distance_m,speed_mps,turn_rate_rps)" : "3 fields (time_s,distance_m,speed_mps)";
  std::vector<MotionCsvSample> samples;
  while (reader.next(record)) {
    const std::string where = "--motion: " + path + ":" + std::to_string(record.line);
    if (!record.problem.empty()) throw std::runtime_error(where + ": " + record.problem);
    const std::vector<std::string>& f = record.fields;
    if (f.size() != (with_turn ? 4u : 3u))
      throw std::runtime_error(where + ": expected " + fields + ", got '" + record.text + "'");
    MotionCsvSample s{number(f[0], where, "time_s"), number(f[1], where, "distance_m"), number(f[2], where, "speed_mps"),
                      with_turn ? number(f[3], where, "turn_rate_rps") : 0.0};
    if (!samples.empty() && s.time_s < samples.back().time_s)
      throw std::runtime_error(where + ": time_s " + f[0] + " goes back in time");
    samples.push_back(s);
  }
  if (samples.empty()) throw std::runtime_error("--motion: '" + path + "' has no samples");
  return samples;
}

void addMotionOptions(CLI::App& command, MotionOptions& options) {
  command.add_option("--motion", options.file,
                     "Robot motion CSV (time_s,distance_m,speed_mps[,turn_rate_rps] in the frames' time base, e.g. "
                     "sim's motion.csv): frames taken standing are not segmented");
  command.add_option("--window-m", options.window_m, "With --motion: segmentation window in metres of travel (0: by time)")
      ->capture_default_str()
      ->check(keyRange("segmentation.window_m"));
}

std::optional<MotionReplay> openMotion(const MotionOptions& options, std::size_t sources, const std::string& command,
                                       FiedlerSegmenterConfig& config) {
  if (options.window_m > 0 && options.file.empty()) throw std::invalid_argument(command + ": --window-m needs --motion");
  if (!options.file.empty() && sources > 1)
    throw std::invalid_argument(command + ": --motion takes one SOURCE (the motion file has one time base)");
  config.window_m = options.window_m;
  if (const std::string problem = config.validate(); !problem.empty()) throw std::invalid_argument(command + ": " + problem);
  if (options.file.empty()) return std::nullopt;
  return MotionReplay(readMotionCsv(options.file));
}

std::string motionSummary(const FiedlerSegmentationStage& stage, const MotionOptions& options, const std::string& command) {
  std::string text = command + ": motion from " + options.file + ": " + std::to_string(stage.motionSamples()) +
                     " samples, " + std::to_string(stage.skippedFrames()) + " frames taken standing (not segmented)";
  if (stage.refusedMotionSamples() > 0) text += ", " + std::to_string(stage.refusedMotionSamples()) + " samples refused";
  return text;
}

void MotionReplay::feedUpTo(double frame_time_s, FiedlerSegmentationStage& stage) {
  while (next_ < samples_.size() && samples_[next_].time_s <= frame_time_s) {
    const MotionCsvSample& s = samples_[next_++];
    stage.addMotion(MotionSample{s.time_s, s.distance_m, s.speed_mps, s.turn_rate_rps});
  }
}

}  // namespace toposlam::cli
