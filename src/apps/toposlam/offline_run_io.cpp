// Shared pieces of `toposlam segment` and `toposlam map` (see offline_run_io.hpp).
#include "offline_run_io.hpp"

#include <cstdio>
#include <stdexcept>
#include <system_error>

#ifdef TOPOSLAM_HAVE_SOURCES
#include "toposlam/io/source_factory.hpp"
#endif

namespace toposlam::cli {

std::unique_ptr<FrameSource> openSource(const std::string& uri) {
#ifdef TOPOSLAM_HAVE_SOURCES
  return openFrameSource(uri);
#else
  throw FrameSourceError("cannot open '" + uri +
                         "': this build has no frame sources (toposlam_sources was not "
                         "built; see io/source_factory.hpp)");
#endif
}

OutputFile openOutput(const std::filesystem::path& path) { return OutputFile(path); }

void createRunFolder(const std::string& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error || !std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir + ": cannot create the output folder" +
                             (error ? " (" + error.message() + ")" : std::string()));
  }
}

void writeTimingCsv(const std::filesystem::path& path, const std::vector<FrameTiming>& rows) {
  OutputFile out = openOutput(path);
  out << "frame,fingerprint_ms,segment_ms,filter_ms\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    char line[112];
    std::snprintf(line, sizeof(line), "%zu,%.4f,%.4f,", i, rows[i].fingerprint_ms, rows[i].segment_ms);
    out << line;
    if (rows[i].filter_ms) {
      std::snprintf(line, sizeof(line), "%.4f", *rows[i].filter_ms);
      out << line;
    }
    out << '\n';
  }
  out.commit();
}

void addSegmentationOptions(CLI::App& command, SegmentationOptions& options) {
  FiedlerSegmenterConfig& c = options.config;
  command.add_option("--window", c.window, "Segmentation: sliding window in frames")
      ->capture_default_str()
      ->check(CLI::Range(3, 1000));
  command.add_option("--gamma", c.valley.gamma, "Segmentation: minimum lambda2 of a peak, [0, n/(n-1)]")
      ->capture_default_str();
  command.add_option("--delta", c.valley.delta,
                     "Segmentation: minimum lambda2 swing between peak and valley, [0, gamma]")
      ->capture_default_str();
  command.add_option("--similarity-floor", c.similarity_floor,
                     "Segmentation: subtracted from every similarity before the affinity, [0, 1)")
      ->capture_default_str();
  command.add_option("--min-keypoints", c.min_keypoints,
                     "Segmentation: drop places whose representative has fewer keypoints")
      ->capture_default_str();
  command.add_option("--cut", options.cut,
                     "Segmentation: where a place ends: window-split (best split of the valley's window) or "
                     "valley-frame")
      ->capture_default_str();
}

FiedlerSegmenterConfig segmenterConfig(const SegmentationOptions& options, const std::string& command) {
  FiedlerSegmenterConfig config = options.config;
  config.cut_placement = parseCutPlacement(options.cut);
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument(command + ": " + problem);
  }
  return config;
}

}  // namespace toposlam::cli
