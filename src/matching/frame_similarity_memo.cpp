// The newest frame's similarities, remembered for one frame: see frame_similarity_memo.hpp.
#include "toposlam/matching/frame_similarity_memo.hpp"

namespace toposlam {

void FrameSimilarityMemo::beginFrame(const Fingerprint* newest) {
  with_newest_.clear();
  newest_ = newest;
}

void FrameSimilarityMemo::endFrame() {
  with_newest_.clear();
  newest_ = nullptr;
}

double FrameSimilarityMemo::symmetricSimilarity(const Fingerprint& a, const Fingerprint& b) const {
  if (newest_ == nullptr || &b != newest_ || &a == newest_) {
    ++computed_;
    return measure_.symmetricSimilarity(a, b);
  }
  for (auto it = with_newest_.rbegin(); it != with_newest_.rend(); ++it)
    if (it->first == &a) {
      ++remembered_;
      return it->second;
    }
  ++computed_;
  const double value = measure_.symmetricSimilarity(a, b);
  with_newest_.emplace_back(&a, value);
  return value;
}

}  // namespace toposlam
