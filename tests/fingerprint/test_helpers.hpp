// Synthetic frames for the fingerprint tests.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace toposlam::test {

/// A mid-grey frame with full-height dark vertical bars of the given width starting at `columns`.
inline cv::Mat barsFrame(int width, int height, const std::vector<int>& columns, int bar_width = 6,
                         int bar_height = -1) {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(170, 170, 170));
  if (bar_height < 0) bar_height = height;
  const int top = (height - bar_height) / 2;
  for (int c : columns) image(cv::Rect(c, top, bar_width, bar_height)).setTo(cv::Scalar(40, 40, 40));
  return image;
}

inline std::string samplePath(int index) {
  return std::string(TOPOSLAM_SAMPLES_DIR) + "/samples/" + std::to_string(index) + ".jpg";
}

inline cv::Mat sampleFrame(int index) { return cv::imread(samplePath(index), cv::IMREAD_COLOR); }

}  // namespace toposlam::test
