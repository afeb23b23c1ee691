// Test helpers: a SimilarityMeasure that reads a hand-made table instead of matching fingerprints, and
// that counts its calls. A fake fingerprint carries its frame id in image_width and its keypoint
// count in `keypoints`, which is all the table and the segmenter look at.
#pragma once

#include <atomic>
#include <functional>
#include <memory>

#include <opencv2/core.hpp>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/matching/similarity_measure.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

namespace toposlam::test {

inline std::shared_ptr<const Fingerprint> fakeFingerprint(int id, int keypoints = 50) {
  auto fingerprint = std::make_shared<Fingerprint>();
  fingerprint->image_width = id;
  fingerprint->keypoints.resize(static_cast<std::size_t>(keypoints));
  return fingerprint;
}

/// The thesis' segmentation settings (window 25, gamma 0.5, delta 0.25), which the hand-made streams
/// check the thesis' numbers with; our defaults differ (docs/segmentation.md).
inline FiedlerSegmenterConfig thesisConfig() {
  FiedlerSegmenterConfig config;
  config.window = 25;
  config.valley = {0.5, 0.25};
  return config;
}

/// similarity(reference, query) = table(reference id, query id).
class TableSimilarity : public SimilarityMeasure {
 public:
  explicit TableSimilarity(std::function<double(int, int)> table) : table_(std::move(table)) {}
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    ++calls_;
    return table_(reference.image_width, query.image_width);
  }
  long calls() const { return calls_; }
  void resetCalls() { calls_ = 0; }

 private:
  std::function<double(int, int)> table_;
  mutable std::atomic<long> calls_{0};
};

}  // namespace toposlam::test
