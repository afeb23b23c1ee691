// Loads the bundled real sample frames (or any image folder) for benchmarks, in natural order.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace toposlam::cli {

/// The default folder of sample frames: $TOPOSLAM_SAMPLES, else the source tree's bundled copy.
std::string defaultSamplesFolder();
/// Every readable image in `folder` (natural order), resized to `size` when it is not empty.
std::vector<cv::Mat> loadSampleFrames(const std::string& folder, cv::Size size = {});

}  // namespace toposlam::cli
