// `toposlam report RUN_DIR [--truth ...] [--frames DIR]... [--out report.html]`: one self-contained HTML
// page for a run folder (see include/toposlam/eval/report.hpp for the figures). Thumbnails come from the
// run's frames: `--frames DIR` (one per traversal, in order), else RUN_DIR/frames/, else the folders
// listed in RUN_DIR/source.txt (one source URI per line; `images:DIR` or a plain folder). A frame is
// found by its frames.csv `name` in its source's folder, or by its position there when that folder holds
// none of the run's names (see thumbnailPaths).
//
// RUN_DIR may be `lcmlog:FILE`, toposlamd's recorded LCM log: it is turned into the run folder FILE.run/
// first (lcmlog_run_folder.hpp; channel names from toposlamd's config, found as toposlamd finds it).
// RUN_DIR may be a map file (map.tsm of `toposlam map` or toposlamd): it is exported into a temporary run
// folder (map_desk.hpp, as `toposlam export` does), reported, and the folder removed; the page goes beside
// the map (MAP without its extension + ".report.html") unless --out says otherwise.
#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "lcm_channels.hpp"
#include "toposlam/platform/output_file.hpp"
#include "eval_cli_options.hpp"
#include "toposlam/core/natural_order.hpp"
#include "toposlam/eval/report.hpp"
#include "toposlam/run_folder/run_folder.hpp"
#include "toposlam/io/image_file.hpp"
#include "lcmlog_run_folder.hpp"
#include "map_desk.hpp"
#include "toposlam/platform/file_system.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/config/daemon_config.hpp"

namespace toposlam::cli {

namespace {

namespace fs = std::filesystem;

struct ReportCommandOptions {
  std::string run_dir;
  std::vector<std::string> truth;
  std::vector<std::string> frames;
  std::string out;
  std::string figures;
  std::string title;
  eval::EvalOptions eval;
  int thumbnails = 96;
  bool json = false;
  std::string map;  ///< the map file RUN_DIR named, when it was one (run_dir is then its export)
};

std::vector<fs::path> frameFolders(const ReportCommandOptions& o, std::vector<std::string>& warnings) {
  std::vector<fs::path> folders;
  for (const auto& f : o.frames) {
    if (!fs::is_directory(f)) throw std::invalid_argument("--frames: '" + f + "' is not a folder");
    folders.emplace_back(f);
  }
  if (!folders.empty()) return folders;
  const fs::path run(o.run_dir);
  if (fs::is_directory(run / run_files::kFramesFolder)) return {run / run_files::kFramesFolder};
  for (const std::string& line : loadSources(run)) {
    std::string path = line.rfind("images:", 0) == 0 ? line.substr(7) : line;
    if (fs::is_directory(path)) {
      folders.emplace_back(path);
    } else {
      warnings.push_back("source.txt: cannot show frames of '" + line +
                         "' (not an image folder); give --frames DIR");
    }
  }
  return folders;
}

std::vector<std::string> imageFiles(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".jpg" || ext == ".jpeg" || ext == ".png" || ext == ".bmp" || ext == ".ppm" || ext == ".pgm") {
      names.push_back(entry.path().filename().string());
    }
  }
  sortNatural(names);
  return names;
}

/// The image file of each of `frames` (empty path = not found). Frames are looked up per source of the run
/// (time going back), one folder each: by their frames.csv name when the source's folder holds the run's
/// names at all, else by position in the folder (sources without file names, e.g. sim: or video:). A named
/// frame missing from a folder that holds the others stays missing rather than being replaced by its
/// neighbour in the listing.
std::vector<fs::path> thumbnailPaths(const RunData& run, const std::vector<std::int64_t>& frames,
                                     const std::vector<fs::path>& folders) {
  const std::vector<std::int64_t>& starts = run.traversal_starts;
  auto sourceOf = [&](std::int64_t f) { return static_cast<std::size_t>(eval::traversalOf(f, starts)); };
  auto nameOf = [&](std::int64_t f) -> const std::string& {
    return run.frames[static_cast<std::size_t>(f)].name;
  };
  std::vector<bool> by_name(folders.size(), false);
  for (std::int64_t f : frames) {
    const std::size_t source = sourceOf(f);
    if (source < folders.size() && !by_name[source] && !nameOf(f).empty() &&
        fs::exists(folders[source] / nameOf(f))) {
      by_name[source] = true;
    }
  }
  std::vector<std::vector<std::string>> listings(folders.size());
  std::vector<fs::path> paths;
  for (std::int64_t f : frames) {
    const std::size_t source = sourceOf(f);
    fs::path path;
    if (source >= folders.size()) {
      // more sources than frame folders: nothing to show
    } else if (by_name[source]) {
      if (!nameOf(f).empty() && fs::exists(folders[source] / nameOf(f))) path = folders[source] / nameOf(f);
    } else {
      if (listings[source].empty()) listings[source] = imageFiles(folders[source]);
      const auto index = static_cast<std::size_t>(f - starts[source]);
      if (index < listings[source].size()) path = folders[source] / listings[source][index];
    }
    paths.push_back(path);
  }
  return paths;
}

/// The picture of frame `f`'s place (its representative's, read into `by_frame`), or "" when it has none.
std::string placePicture(const RunData& run, std::int64_t f, const std::map<std::int64_t, std::string>& by_frame) {
  const int place = run.frames[static_cast<std::size_t>(f)].place;
  if (place < 0) return "";
  for (const PlaceRecord& p : run.places) {
    if (p.place != place) continue;
    const auto it = by_frame.find(p.representative);
    return it == by_frame.end() ? "" : it->second;
  }
  return "";
}

/// A picture of the run as BGR; empty when it cannot be read (the report shows it without).
cv::Mat readPicture(const fs::path& path) {
  try {
    return readImageFileChecked(path.string(), ImageColor::Bgr);
  } catch (const ImageReadError&) {
    return {};
  }
}

std::string thumbnailDataUri(const fs::path& path) {
  const cv::Mat image = readPicture(path);
  if (image.empty()) return "";
  const int width = 160;
  const int height = std::max(1, image.rows * width / std::max(1, image.cols));
  cv::Mat small;
  cv::resize(image, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  const std::vector<std::uint8_t> jpeg = encodeImage(small, ImageFormat::Jpeg, 80);
  return "data:image/jpeg;base64," + eval::base64Encode(jpeg);
}

/// A picture as a PNG data URI, at most 560 px wide; empty when it cannot be read.
std::string pictureDataUri(const fs::path& path) {
  cv::Mat image = readPicture(path);
  if (image.empty()) return "";
  if (image.cols > 560) cv::resize(image, image, cv::Size(560, std::max(1, image.rows * 560 / image.cols)), 0, 0, cv::INTER_AREA);
  const std::vector<std::uint8_t> png = encodeImage(image, ImageFormat::Png);
  return "data:image/png;base64," + eval::base64Encode(png);
}

/// The report's date, UTC; SOURCE_DATE_EPOCH (seconds) replaces the clock for reproducible pages.
std::string reportTime() {
  std::time_t now = std::time(nullptr);
  if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH"); epoch != nullptr && *epoch != '\0') {
    char* end = nullptr;
    const long long seconds = std::strtoll(epoch, &end, 10);
    if (end != epoch && *end == '\0' && seconds >= 0) now = static_cast<std::time_t>(seconds);
  }
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[40];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &utc);
  return text;
}

/// `lcmlog:FILE`: converts the log into FILE.run and returns that folder; any other RUN_DIR as it is.
std::string runFolderOf(const std::string& run_dir) {
  if (run_dir.rfind("lcmlog:", 0) != 0) return run_dir;
  const std::string log = run_dir.substr(7);
  if (log.empty()) throw std::invalid_argument("run_dir: 'lcmlog:' names no file (lcmlog:FILE)");
  DaemonConfig config;
  if (const std::string path = defaultDaemonConfigPath(); fs::exists(path)) config = loadDaemonConfig(path);
  const LcmChannels channels = channelsOf(config.lcm);
  const LoggedRun run = readLoggedRun(log, channels);
  const std::string folder = log + ".run";
  writeRunFolderFromLog(run, log, folder);
  std::cerr << "converted " << log << " (" << run.events << " events: " << run.frames.size() << " place estimates, "
            << run.places.size() << " places) into the run folder " << folder << "\n";
  return folder;
}

/// A map file given as RUN_DIR: exported into `folder`; the report's default file and title follow the map.
void exportMapForReport(ReportCommandOptions& o, const fs::path& folder) {
  const fs::path map_path(o.run_dir);
  const DeskMap map = openDeskMap(map_path, "report");
  writeExportedRun(map, folder);
  std::cerr << "report: exported " << map_path.string() << " (" << map.topology->observations() << " places, "
            << nodeCount(map) << " nodes) into a temporary run folder\n";
  if (o.out.empty()) o.out = (map_path.parent_path() / map_path.stem()).string() + ".report.html";
  if (o.title.empty()) o.title = "toposlam report: " + map_path.filename().string();
  o.map = o.run_dir;
  o.run_dir = folder.string();
}

void runReport(ReportCommandOptions o) {
  std::optional<TemporaryFolder> exported;
  std::error_code error;
  const bool missing_map = !fs::exists(o.run_dir, error) && fs::path(o.run_dir).extension() == ".tsm";
  if (fs::is_regular_file(o.run_dir, error) || missing_map) {
    exported.emplace("toposlam-report-");
    exportMapForReport(o, exported->path() / "run");
  }
  o.run_dir = runFolderOf(o.run_dir);
  eval::ReportInputs in;
  in.run = loadRun(o.run_dir);
  in.title = o.title.empty()
                 ? "toposlam report: " + fs::path(o.run_dir).lexically_normal().filename().string()
                 : o.title;
  in.generator = "toposlam " TOPOSLAM_VERSION;
  in.generated = reportTime();
  if (!o.truth.empty()) {
    // The simulator writes its pictures beside labels.csv: shown as they are.
    for (const std::string& t : o.truth) {
      const fs::path folder = fs::path(t).parent_path();
      for (const auto& [file, caption] : {std::pair<const char*, const char*>{"map.png", "floor plan and route"},
                                          {"loop_closure.png", "ground-truth loop closures"}}) {
        const fs::path picture = (folder.empty() ? fs::path(".") : folder) / file;
        if (!fs::exists(picture)) continue;
        const std::string uri = pictureDataUri(picture);
        if (!uri.empty()) in.pictures.emplace_back(std::string(caption) + " (" + picture.string() + ")", uri);
      }
    }
    const eval::Truth truth = eval::loadTruth(o.truth);
    in.eval = eval::evaluate(in.run, truth, o.eval);
    if (truth.kind == eval::Truth::Kind::Labels) {
      for (const auto& l : truth.labels) in.rooms.push_back(l.room);
    }
  }

  const std::vector<fs::path> folders = frameFolders(o, in.warnings);
  in.thumbnails.assign(in.run.frames.size(), "");
  if (folders.empty()) {
    in.warnings.push_back(
        "no frames found (no --frames DIR, RUN_DIR/frames or RUN_DIR/source.txt): figures without "
        "thumbnails");
  } else {
    const std::vector<std::int64_t> frames = eval::framesForThumbnails(in.run, o.thumbnails);
    const std::vector<fs::path> paths = thumbnailPaths(in.run, frames, folders);
    // Folders of one picture per place (toposlamd's log carries its representatives' only): a frame
    // without a picture of its own shows its place's. Elsewhere a missing frame is reported, not replaced.
    std::map<std::int64_t, std::string> by_frame;
    for (std::size_t k = 0; k < frames.size(); ++k)
      if (!paths[k].empty()) by_frame[frames[k]] = thumbnailDataUri(paths[k]);
    std::set<std::int64_t> representatives;
    for (const PlaceRecord& p : in.run.places) representatives.insert(p.representative);
    const bool per_place = !by_frame.empty() && std::all_of(by_frame.begin(), by_frame.end(), [&](const auto& e) {
      return e.second.empty() || representatives.count(e.first) != 0;
    });
    int missing = 0, from_place = 0;
    for (const std::int64_t f : frames) {
      std::string uri = by_frame.count(f) != 0 ? by_frame[f] : "";
      if (uri.empty() && per_place) uri = placePicture(in.run, f, by_frame);
      if (!uri.empty() && (by_frame.count(f) == 0 || by_frame[f].empty())) ++from_place;
      if (uri.empty()) ++missing;
      in.thumbnails[static_cast<std::size_t>(f)] = std::move(uri);
    }
    if (from_place > 0)
      std::cerr << "report: " << from_place << " frames without a picture of their own show their place's\n";
    if (missing > 0)
      in.warnings.push_back(std::to_string(missing) + " frames could not be read for thumbnails");
  }

  const fs::path out = o.out.empty() ? fs::path(o.run_dir) / "report.html" : fs::path(o.out);
  writeFileAtomically(out, eval::renderReportHtml(in));  // temporary name, checked, renamed
  if (!o.figures.empty()) {
    fs::create_directories(o.figures);
    for (const auto& [name, svg] : eval::renderReportFigures(in)) {
      writeFileAtomically(fs::path(o.figures) / name, svg);
    }
    std::cout << "wrote the figures as SVG files into " << o.figures << "\n";
  }
  for (const auto& w : in.warnings) std::cerr << "report: warning: " << w << "\n";
  if (o.json) {
    int thumbnails = 0;
    for (const std::string& t : in.thumbnails) thumbnails += t.empty() ? 0 : 1;
    JsonWriter json(std::cout);
    json.beginObject()
        .field("report", out.string())
        .field("bytes", static_cast<std::int64_t>(fs::file_size(out)))
        .field("run", o.map.empty() ? o.run_dir : o.map)
        .field("frames", in.run.frames.size())
        .field("places", in.run.places.size())
        .field("thumbnails", thumbnails)
        .field("evaluated", in.eval.has_value())
        .field("warnings", in.warnings.size())
        .endObject();
    std::cout << "\n" << std::flush;
    return;
  }
  std::cout << "wrote " << out.string() << " (" << fs::file_size(out) / 1024 << " KiB)\n";
}

}  // namespace

void addReportCommand(CLI::App& app) {
  auto options = std::make_shared<ReportCommandOptions>();
  auto* cmd = app.add_subcommand("report",
                                 "One self-contained HTML page with the figures and tables of a run folder");
  cmd->add_option("run_dir", options->run_dir,
                  "Run folder written by `toposlam segment` or `toposlam map`, a map file (map.tsm, exported to a "
                  "temporary run folder first), or lcmlog:FILE (toposlamd's LCM log, converted into FILE.run/)")
      ->required();
  cmd->add_option("--truth", options->truth,
                  "Ground truth as for `toposlam eval` (adds the evaluation tables)");
  cmd->add_option("--frames", options->frames,
                  "Folder of the run's frames, one per source in order (thumbnails)");
  cmd->add_option("--out", options->out,
                  "Output HTML file (default RUN_DIR/report.html; for a map file, MAP.report.html beside it)");
  cmd->add_option("--title", options->title, "Page title");
  cmd->add_option("--figures", options->figures,
                  "Also write each figure as a standalone SVG file into this folder");
  cmd->add_option("--thumbnails", options->thumbnails, "About this many evenly spaced frame thumbnails")
      ->check(CLI::Range(0, 2000))
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print a summary as one JSON object (file, size, frames, places, thumbnails)");
  addEvalMeasureOptions(*cmd, options->eval);
  cmd->callback([options] { runReport(*options); });
}

}  // namespace toposlam::cli
