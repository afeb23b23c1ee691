// The segmentation stage's one similarity measure: the newest frame's symmetric similarities, remembered
// for the span of that frame. The sequence detector (PlaceSequenceEvidence) and the segmenter
// (FiedlerSegmenter) both compare the newest frame with the same earlier frames (the segmenter's window,
// its place samples); each pair is now computed once. Values are those of the measure it wraps, bit for
// bit: only symmetricSimilarity(earlier, newest), with the newest second (the order both callers use), is
// remembered.
//
// Not thread-safe (unlike SimilarityMeasure in general): one stage, one thread, one frame at a time. Its
// keys are addresses, valid only between beginFrame() and endFrame(), while the stage holds every
// fingerprint compared.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "toposlam/matching/similarity_measure.hpp"

namespace toposlam {

class FrameSimilarityMemo : public SimilarityMeasure {
 public:
  explicit FrameSimilarityMemo(const SimilarityMeasure& measure) : measure_(measure) {}

  /// From now until endFrame(), symmetricSimilarity(x, *newest) is computed once per x.
  void beginFrame(const Fingerprint* newest);
  /// Forgets the frame's similarities (no address is kept past the frame).
  void endFrame();

  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    return measure_.similarity(reference, query);
  }
  double symmetricSimilarity(const Fingerprint& a, const Fingerprint& b) const override;

  /// Pairs computed by the wrapped measure, and pairs answered from the memo, since construction.
  std::int64_t computed() const { return computed_; }
  std::int64_t remembered() const { return remembered_; }

 private:
  const SimilarityMeasure& measure_;
  const Fingerprint* newest_ = nullptr;
  /// The frame's pairs in the order they were computed; its capacity is kept from frame to frame (no
  /// allocation on the frame path once grown). Searched from the end: the segmenter asks for the latest frames.
  mutable std::vector<std::pair<const Fingerprint*, double>> with_newest_;
  mutable std::int64_t computed_ = 0;
  mutable std::int64_t remembered_ = 0;
};

}  // namespace toposlam
