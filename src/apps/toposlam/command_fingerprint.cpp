// `toposlam fingerprint IMAGE...`: prints each image's VPACK fingerprint (edges, subregions, histograms,
// keypoint counts), as text or JSON, and optionally draws it (thesis Figure 3.11).
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <stdexcept>


#include "commands.hpp"
#include "image_input.hpp"
#include "offline_run_io.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/core/worker_pool.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/platform/thread_os.hpp"

namespace toposlam::cli {

namespace {

struct FingerprintOptions {
  std::vector<std::string> images;
  std::string keypoints = "orb";
  bool json = false;
  std::string draw;
  int workers = 1;
};

std::string drawPath(const std::string& pattern, const std::string& image, std::size_t count) {
  if (count == 1) return pattern;
  std::filesystem::path p(pattern);
  const std::string stem = std::filesystem::path(image).stem().string();
  return (p.parent_path() / (p.stem().string() + "-" + stem + p.extension().string())).string();
}

void printText(const std::string& path, const Fingerprint& f) {
  std::cout << path << ": " << f.image_width << "x" << f.image_height << ", " << f.edge_columns.size()
            << " edges, " << f.subregions.size() << " subregions, " << f.keypointCount() << " "
            << toString(f.backend) << " keypoints\n  edges:";
  for (int c : f.edge_columns) std::cout << ' ' << c;
  std::cout << "\n";
  for (std::size_t i = 0; i < f.subregions.size(); ++i) {
    const Subregion& s = f.subregions[i];
    std::cout << "  [" << std::setw(4) << s.column_begin << "," << std::setw(4) << s.column_end << ") kp "
              << std::setw(3) << s.keypointCount() << "  hist";
    for (float v : s.histogram) std::cout << ' ' << std::fixed << std::setprecision(3) << v;
    std::cout << "\n";
  }
}

void writeJson(JsonWriter& json, const std::string& path, const Fingerprint& f) {
  json.beginObject().field("image", path).field("width", f.image_width).field("height", f.image_height);
  json.field("keypoint_backend", toString(f.backend)).field("keypoints", f.keypointCount());
  json.key("edges").beginArray();
  for (int c : f.edge_columns) json.value(c);
  json.endArray();
  json.key("subregions").beginArray();
  for (const Subregion& s : f.subregions) {
    json.beginObject().field("column_begin", s.column_begin).field("column_end", s.column_end);
    json.field("keypoints", s.keypointCount());
    json.key("histogram").beginArray();
    for (float v : s.histogram) json.value(static_cast<double>(v));
    json.endArray().endObject();
  }
  json.endArray().endObject();
}

}  // namespace

void addFingerprintCommand(CLI::App& app) {
  auto options = std::make_shared<FingerprintOptions>();
  auto* cmd = app.add_subcommand("fingerprint", "Print the VPACK fingerprint of images (thesis chapter 3.2)");
  cmd->add_option("images", options->images, "Image files")->required();
  addKeypointBackendOption(*cmd, options->keypoints);
  cmd->add_flag("--json", options->json, "Print JSON instead of text");
  cmd->add_option("--draw", options->draw,
                  "Write the frame with edges and keypoints drawn (OUT.png; OUT-<name>.png for several images)");
  cmd->add_option("--workers", options->workers, "Worker threads for per-subregion work")
      ->check(CLI::Range(1, 64));
  cmd->callback([options] {
    VpackConfig config;
    config.keypoints.backend = parseKeypointBackend(options->keypoints);
    WorkerPool pool(options->workers, namedWorkers("fingerprint"));
    VpackExtractor extractor(config, &pool);
    JsonWriter json(std::cout);
    if (options->json && options->images.size() > 1) json.beginArray();
    int failures = 0;
    for (const std::string& path : options->images) {
      try {
        const cv::Mat image = readImageFile(path);
        const Fingerprint f = fingerprintImage(extractor, image, path);
        if (options->json)
          writeJson(json, path, f);
        else
          printText(path, f);
        if (!options->draw.empty()) {
          const std::string out = drawPath(options->draw, path, options->images.size());
          writeImageFile(out, drawFingerprint(image, f));  // temporary name, checked, renamed
        }
      } catch (const std::exception& e) {
        // One bad image does not stop the others; the exit status says something failed.
        std::cerr << "toposlam fingerprint: " << e.what() << "\n";
        ++failures;
      }
    }
    if (options->json && options->images.size() > 1) json.endArray();
    if (failures > 0)
      throw std::runtime_error(std::to_string(failures) + " of " + std::to_string(options->images.size()) +
                               " images could not be fingerprinted");
  });
}

}  // namespace toposlam::cli
