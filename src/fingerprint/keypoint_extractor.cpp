// A few robust keypoints per frame (thesis section 3.2.3); see the header for the selection scheme.
#include "toposlam/fingerprint/keypoint_extractor.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string KeypointConfig::validate() const {
  std::ostringstream e;
  if (max_keypoints < 0 || max_keypoints > 10000)
    e << "fingerprint.keypoints.max_keypoints: " << max_keypoints << " is outside [0, 10000]";
  else if (threshold_iterations < 0 || threshold_iterations > 64)
    e << "fingerprint.keypoints.threshold_iterations: " << threshold_iterations << " is outside [0, 64]";
  else if (candidate_limit < max_keypoints || candidate_limit > 100000)
    e << "fingerprint.keypoints.candidate_limit: " << candidate_limit << " is outside [max_keypoints, 100000]";
  else if (orb_levels < 1 || orb_levels > 16)
    e << "fingerprint.keypoints.orb_levels: " << orb_levels << " is outside [1, 16]";
  else if (orb_fast_threshold < 1 || orb_fast_threshold > 254)
    e << "fingerprint.keypoints.orb_fast_threshold: " << orb_fast_threshold << " is outside [1, 254]";
  return e.str();
}

KeypointExtractor::KeypointExtractor(const KeypointConfig& config) : config_(config) {
  if (std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
}

cv::Ptr<cv::Feature2D> KeypointExtractor::createDetector() const {
  const KeypointConfig& c = config_;
  switch (c.backend) {
    case KeypointBackend::Orb:
      return cv::ORB::create(c.candidate_limit, 1.2f, c.orb_levels, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                             c.orb_fast_threshold);
    case KeypointBackend::Sift:
      // Contrast floor below OpenCV's default 0.04: selection per subregion raises it where needed.
      return cv::SIFT::create(c.candidate_limit, 3, 0.02, 10, 1.6);
    case KeypointBackend::Brisk:
      return cv::BRISK::create(20, 3, 1.0f);
    case KeypointBackend::Akaze:
      return cv::AKAZE::create(cv::AKAZE::DESCRIPTOR_MLDB, 0, 3, 0.0005f, 4, 4, cv::KAZE::DIFF_PM_G2);
  }
  throw std::invalid_argument("unknown keypoint backend");
}

KeypointCandidates KeypointExtractor::detect(const cv::Mat& grey) const {
  KeypointCandidates out;
  if (config_.max_keypoints == 0) return out;
  detect(*createDetector(), grey, out);
  return out;
}

void KeypointExtractor::detect(cv::Feature2D& detector, const cv::Mat& grey, KeypointCandidates& out) const {
  out.keypoints.clear();
  if (config_.max_keypoints == 0) {
    out.descriptors.release();
    return;
  }
  detector.detectAndCompute(grey, cv::noArray(), out.keypoints, out.descriptors);
  if (out.keypoints.size() > static_cast<std::size_t>(config_.candidate_limit)) {
    // BRISK and AKAZE have no cap of their own: keep the strongest candidates, in their order, moving
    // them forward in place (order is ascending, so a row is only ever copied to a lower one).
    std::vector<int> order(out.keypoints.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return out.keypoints[a].response > out.keypoints[b].response; });
    order.resize(config_.candidate_limit);
    std::sort(order.begin(), order.end());
    for (std::size_t r = 0; r < order.size(); ++r) {
      const int from = order[r];
      if (from == static_cast<int>(r)) continue;
      out.keypoints[r] = out.keypoints[static_cast<std::size_t>(from)];
      out.descriptors.row(from).copyTo(out.descriptors.row(static_cast<int>(r)));
    }
    out.keypoints.resize(order.size());
    out.descriptors = out.descriptors.rowRange(0, static_cast<int>(order.size()));
  }
}

std::vector<int> KeypointExtractor::select(const KeypointCandidates& candidates, int column_begin,
                                           int column_end, int budget) const {
  std::vector<int> inside;
  for (int i = 0; i < static_cast<int>(candidates.keypoints.size()); ++i) {
    const float x = candidates.keypoints[i].pt.x;
    if (x >= static_cast<float>(column_begin) && x < static_cast<float>(column_end)) inside.push_back(i);
  }
  auto strongest_first = [&](int a, int b) {
    const float ra = candidates.keypoints[a].response, rb = candidates.keypoints[b].response;
    return ra != rb ? ra > rb : a < b;
  };
  if (static_cast<int>(inside.size()) > budget) {
    // Raise the response threshold by bisection between the weakest and the strongest response;
    // keep the largest set that fits the budget, or everything above the last threshold if none did.
    float low = candidates.keypoints[inside[0]].response, high = low;
    for (int i : inside) {
      low = std::min(low, candidates.keypoints[i].response);
      high = std::max(high, candidates.keypoints[i].response);
    }
    auto count_above = [&](float t) {
      return static_cast<int>(std::count_if(inside.begin(), inside.end(),
                                            [&](int i) { return candidates.keypoints[i].response > t; }));
    };
    float threshold = low;
    bool fitted = false;
    float best_fit = high;
    for (int iteration = 0; iteration < config_.threshold_iterations; ++iteration) {
      threshold = low + (high - low) / 2.f;
      const int n = count_above(threshold);
      if (n > budget) {
        low = threshold;
      } else {
        fitted = true;
        best_fit = threshold;
        high = threshold;
        if (n == budget) break;
      }
    }
    const float keep_above = fitted ? best_fit : low;
    // Responses exactly at the lowest value are kept only when no threshold was ever applied.
    if (config_.threshold_iterations > 0)
      std::erase_if(inside, [&](int i) { return !(candidates.keypoints[i].response > keep_above); });
  }
  std::sort(inside.begin(), inside.end(), strongest_first);
  return inside;
}

std::vector<int> KeypointExtractor::budgets(const std::vector<Subregion>& subregions, int image_width) const {
  std::vector<int> result(subregions.size(), 0);
  if (subregions.empty() || image_width <= 0) return result;
  // Largest-remainder apportionment of max_keypoints by subregion width.
  std::vector<std::pair<double, int>> remainders;
  int assigned = 0;
  for (std::size_t i = 0; i < subregions.size(); ++i) {
    const double exact = static_cast<double>(config_.max_keypoints) * subregions[i].width() / image_width;
    result[i] = static_cast<int>(std::floor(exact));
    assigned += result[i];
    remainders.emplace_back(exact - result[i], static_cast<int>(i));
  }
  std::stable_sort(remainders.begin(), remainders.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (int k = 0; assigned < config_.max_keypoints && k < static_cast<int>(remainders.size()); ++k, ++assigned)
    ++result[remainders[k].second];
  return result;
}

}  // namespace toposlam
