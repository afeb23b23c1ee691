// Plain ORB baseline for place recognition: see orb_baseline.hpp.
#include "toposlam/eval/orb_baseline.hpp"

#include <algorithm>
#include <vector>

#include <opencv2/core/hal/hal.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

namespace toposlam::eval {
namespace {

// For each row of `from`, its best row of `to` when it passes the ratio test, else -1.
std::vector<int> ratioMatches(const cv::Mat& from, const cv::Mat& to, double ratio) {
  std::vector<int> best(static_cast<std::size_t>(from.rows), -1);
  for (int a = 0; a < from.rows; ++a) {
    int d1 = 1 << 30, d2 = 1 << 30, arg = -1;
    for (int b = 0; b < to.rows; ++b) {
      const int d = cv::hal::normHamming(from.ptr<uchar>(a), to.ptr<uchar>(b), from.cols);
      if (d < d1) {
        d2 = d1;
        d1 = d;
        arg = b;
      } else if (d < d2) {
        d2 = d;
      }
    }
    if (arg >= 0 && (to.rows == 1 || d1 < ratio * d2)) best[static_cast<std::size_t>(a)] = arg;
  }
  return best;
}

}  // namespace

OrbBaseline::OrbBaseline(const OrbBaselineConfig& config) : config_(config) {}

cv::Mat OrbBaseline::extract(const cv::Mat& image) const {
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4)
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  else
    grey = image;
  cv::Ptr<cv::ORB> orb = cv::ORB::create(std::max(1, config_.keypoints));
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  return descriptors;
}

double OrbBaseline::similarity(const cv::Mat& a, const cv::Mat& b) const {
  if (a.empty() || b.empty() || a.cols != b.cols || a.type() != CV_8U || b.type() != CV_8U) return 0.0;
  const std::vector<int> forward = ratioMatches(a, b, config_.ratio);
  const std::vector<int> backward = ratioMatches(b, a, config_.ratio);
  int good = 0;
  for (int i = 0; i < a.rows; ++i) {
    const int j = forward[static_cast<std::size_t>(i)];
    if (j >= 0 && backward[static_cast<std::size_t>(j)] == i) ++good;
  }
  return static_cast<double>(good) / static_cast<double>(std::min(a.rows, b.rows));
}

}  // namespace toposlam::eval
