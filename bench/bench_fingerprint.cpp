// `toposlam-bench fingerprint`: ms per frame of VPACK extraction, from the camera's buffer (BGR, YUYV,
// grey) to the fingerprint, at 320x240 and 640x480, per keypoint backend and worker count.
#include <iomanip>
#include <iostream>
#include <memory>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "camera_pixels.hpp"
#include "image_input.hpp"
#include "toposlam/core/worker_pool.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/platform/thread_os.hpp"

namespace toposlam::cli {

namespace {

struct FingerprintBenchOptions {
  std::string samples;
  int repeat = 3;
  std::vector<std::string> backends = {"orb", "sift"};
  std::vector<int> workers = {1, 2};
  std::vector<std::string> formats = {"bgr"};
  bool json = false;
};

/// One camera format's way from the buffer to the fingerprint. "-via-bgr": as before issue 18 (every
/// camera frame made BGR, and grey again for edges and keypoints); without: the frame path now.
struct CameraPath {
  std::string name;
  CameraPixelLayout layout = CameraPixelLayout::Bgr;
  bool via_bgr = false;
};

CameraPath parseCameraPath(const std::string& name) {
  if (name == "bgr") return {name, CameraPixelLayout::Bgr, false};
  if (name == "yuyv") return {name, CameraPixelLayout::Yuyv, false};
  if (name == "yuyv-via-bgr") return {name, CameraPixelLayout::Yuyv, true};
  if (name == "grey") return {name, CameraPixelLayout::Grey, false};
  if (name == "grey-via-bgr") return {name, CameraPixelLayout::Grey, true};
  throw CLI::ValidationError("--formats",
                             name + " is not one of bgr, yuyv, yuyv-via-bgr, grey, grey-via-bgr");
}

/// The frame as that camera's buffer (BGR: none, the image is used as it is).
std::vector<std::uint8_t> cameraBuffer(const cv::Mat& bgr, CameraPixelLayout layout) {
  if (layout == CameraPixelLayout::Yuyv) return bgrToYuyv(bgr);
  if (layout == CameraPixelLayout::Grey) {
    cv::Mat grey;
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    return std::vector<std::uint8_t>(grey.datastart, grey.dataend);
  }
  return {};
}

void runFingerprintBench(const FingerprintBenchOptions& o) {
  cv::setNumThreads(1);  // measure our own parallelism, not OpenCV's
  BenchRows rows("fingerprint", o.json);
  rows.text() << "VPACK extraction, " << o.repeat << " passes over the sample frames (" << o.samples << ")\n";
  rows.text()
      << "Times from the camera's buffer (bgr: the decoded image) to the fingerprint, conversion included.\n";
  rows.text() << std::left << std::setw(10) << "size" << std::setw(8) << "kp" << std::setw(14) << "format"
            << std::setw(9) << "workers" << std::right << std::setw(12) << "median ms" << std::setw(10)
            << "p99 ms" << std::setw(10) << "fps" << std::setw(12) << "keypoints" << std::setw(9) << "edges"
            << "\n";
  std::vector<CameraPath> paths;
  for (const std::string& name : o.formats) paths.push_back(parseCameraPath(name));
  for (cv::Size size : {cv::Size(320, 240), cv::Size(640, 480)}) {
    const std::vector<cv::Mat> frames = loadSampleFrames(o.samples, size);
    for (const CameraPath& path : paths) {
      std::vector<std::vector<std::uint8_t>> buffers;
      for (const cv::Mat& frame : frames) buffers.push_back(cameraBuffer(frame, path.layout));
      const auto stride = static_cast<std::size_t>(size.width * bytesPerPixel(path.layout));
      for (const std::string& backend : o.backends) {
        for (int workers : o.workers) {
          VpackConfig config;
          config.keypoints.backend = parseKeypointBackend(backend);
          WorkerPool pool(workers, namedWorkers("bench"));
          VpackExtractor extractor(config, &pool);
          std::vector<double> ms;
          double keypoints = 0, edges = 0;
          for (int pass = 0; pass < o.repeat; ++pass) {
            for (std::size_t k = 0; k < frames.size(); ++k) {
              const std::vector<std::uint8_t>& buffer = buffers[k];
              Stopwatch watch;
              Fingerprint f;
              if (path.layout == CameraPixelLayout::Bgr) {
                f = extractor.extract(frames[k]);
              } else if (path.via_bgr) {
                f = extractor.extract(cameraBufferToBgr(path.layout, buffer.data(), buffer.size(), size.width,
                                                        size.height, stride));
              } else {
                const CameraImages images = cameraBufferToImages(path.layout, buffer.data(), buffer.size(),
                                                                 size.width, size.height, stride);
                f = extractor.extract(images.image, images.grey);
              }
              ms.push_back(watch.elapsedMs());
              keypoints += f.keypointCount();
              edges += static_cast<double>(f.edge_columns.size());
            }
          }
          const TimingSummary s = summarize(ms);
          rows.row({{"width", std::int64_t{size.width}}, {"height", std::int64_t{size.height}}, {"keypoints_backend", backend},
                    {"format", path.name}, {"workers", std::int64_t{workers}}, {"median_ms", s.median_ms},
                    {"p99_ms", s.p99_ms}, {"fps", 1000.0 / s.median_ms},
                    {"keypoints", keypoints / static_cast<double>(ms.size())},
                    {"edges", edges / static_cast<double>(ms.size())}});
          rows.text() << std::left << std::setw(10)
                    << (std::to_string(size.width) + "x" + std::to_string(size.height)) << std::setw(8)
                    << backend << std::setw(14) << path.name << std::setw(9) << workers << std::right
                    << std::fixed << std::setprecision(2) << std::setw(12) << s.median_ms << std::setw(10)
                    << s.p99_ms << std::setw(10) << std::setprecision(1) << 1000.0 / s.median_ms
                    << std::setw(12) << keypoints / ms.size() << std::setw(9) << edges / ms.size() << "\n";
        }
      }
    }
  }
}

}  // namespace

void addBenchFingerprint(CLI::App& bench) {
  auto options = std::make_shared<FingerprintBenchOptions>();
  options->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand("fingerprint", "ms per frame of VPACK extraction (320x240, 640x480)");
  cmd->add_option("--samples", options->samples, "Folder of frames")->capture_default_str();
  cmd->add_option("--repeat", options->repeat, "Passes over the frames")->check(CLI::Range(1, 1000));
  cmd->add_option("--keypoints", options->backends, "Backends to measure")->capture_default_str();
  cmd->add_option("--workers", options->workers, "Worker counts to measure")->capture_default_str();
  cmd->add_option(
         "--formats", options->formats,
         "Camera formats, from the camera's buffer: bgr, yuyv, grey, and yuyv-via-bgr, grey-via-bgr (the "
         "way before issue 18: made BGR, then grey again)")
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the rows as one JSON object (the table goes to stderr)");
  cmd->callback([options] { runFingerprintBench(*options); });
}

}  // namespace toposlam::cli
