// The one interface the later stages (segmentation, topology filter) need from matching: a
// similarity in [0, 1] between two fingerprints. Tests inject fakes with hand-made similarity tables.
#pragma once

#include "toposlam/fingerprint/fingerprint.hpp"

namespace toposlam {

class SimilarityMeasure {
 public:
  virtual ~SimilarityMeasure() = default;
  /// How well `query` matches `reference`, in [0, 1]; not symmetric in general.
  /// Thread-safety: implementations are const and may be called concurrently.
  virtual double similarity(const Fingerprint& reference, const Fingerprint& query) const = 0;
  /// Mean of both directions (chapter 4 needs a symmetric affinity). An implementation may compute both
  /// at once, to the same value.
  virtual double symmetricSimilarity(const Fingerprint& a, const Fingerprint& b) const {
    return 0.5 * (similarity(a, b) + similarity(b, a));
  }
};

}  // namespace toposlam
