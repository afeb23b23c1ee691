// Image input shared by the `toposlam` commands: reading one image file with one behaviour everywhere
// (fingerprint, similarity, localize), the --keypoints option, and the bundled real sample frames
// (or any image folder) for benchmarks, in natural order.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "toposlam/fingerprint/vpack_extractor.hpp"

namespace toposlam::cli {

/// Reads an image file as 8-bit grey (1 channel) or BGR (3 channels): grey files stay grey, colour files
/// lose any alpha channel, 16-bit files are scaled to 8 bits. Throws std::runtime_error
/// "PATH: no such file" or "PATH: not a readable image (corrupt or unsupported format)".
cv::Mat readImageFile(const std::string& path);

/// extractor.extract(image), with any error rethrown as std::runtime_error "PATH: what went wrong".
Fingerprint fingerprintImage(const VpackExtractor& extractor, const cv::Mat& image, const std::string& path);
/// readImageFile(path) then fingerprintImage: every error message starts with the path.
Fingerprint fingerprintImageFile(const VpackExtractor& extractor, const std::string& path);

/// Adds `--keypoints orb|sift|brisk|akaze` (case-insensitive, default shown) bound to `backend`.
CLI::Option* addKeypointBackendOption(CLI::App& command, std::string& backend);

/// The default folder of sample frames: $TOPOSLAM_SAMPLES, else the source tree's bundled copy.
std::string defaultSamplesFolder();
/// Every readable image in `folder` (natural order, read as BGR), resized to `size` when it is not empty.
std::vector<cv::Mat> loadSampleFrames(const std::string& folder, cv::Size size = {});

}  // namespace toposlam::cli
