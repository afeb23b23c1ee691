// Image input for the CLI commands and sample frames for benchmarks: see the header.
#include "image_input.hpp"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "toposlam/core/natural_order.hpp"
#include "toposlam/io/image_file.hpp"

namespace toposlam::cli {

cv::Mat readImageFile(const std::string& path) {
  // ANYCOLOR without ANYDEPTH: 8-bit, grey kept as one channel, colour as BGR (alpha dropped). A truncated
  // file (a JPEG without its end marker) or one over the pixel cap is refused, not decoded half grey.
  return readImageFileChecked(path, ImageColor::AsStored);
}

Fingerprint fingerprintImage(const VpackExtractor& extractor, const cv::Mat& image, const std::string& path) {
  try {
    return extractor.extract(image);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

Fingerprint fingerprintImageFile(const VpackExtractor& extractor, const std::string& path) {
  return fingerprintImage(extractor, readImageFile(path), path);
}

CLI::Option* addKeypointBackendOption(CLI::App& command, std::string& backend) {
  return command.add_option("--keypoints", backend, "Keypoint backend: orb, sift, brisk, akaze")
      ->check(CLI::IsMember({"orb", "sift", "brisk", "akaze"}, CLI::ignore_case))
      ->capture_default_str();
}

std::string defaultSamplesFolder() {
  if (const char* env = std::getenv("TOPOSLAM_SAMPLES")) return env;
  return TOPOSLAM_SAMPLES_DIR "/samples";
}

std::vector<cv::Mat> loadSampleFrames(const std::string& folder, cv::Size size) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(folder)) throw std::runtime_error(folder + ": not a folder of images");
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".jpg" || ext == ".jpeg" || ext == ".png" || ext == ".bmp") names.push_back(entry.path().string());
  }
  sortNatural(names);
  std::vector<cv::Mat> frames;
  for (const auto& name : names) {
    cv::Mat image;
    try {
      image = readImageFileChecked(name, ImageColor::Bgr);
    } catch (const ImageReadError&) {
      continue;
    }
    if (!size.empty() && image.size() != size) cv::resize(image, image, size, 0, 0, cv::INTER_AREA);
    frames.push_back(image);
  }
  if (frames.empty()) throw std::runtime_error(folder + ": no readable images");
  return frames;
}

}  // namespace toposlam::cli
