// Named settings of the fingerprint and the similarity (docs/matching.md, "Presets"):
//   - "thesis": the method exactly as published (chapter 3; 100 keypoints, histograms and keypoints
//     weighted equally, n-gram counts over possible n-grams, Hamming <= 64 bits and ratio 0.9 without
//     a mutual check, a reference without keypoints scored by its histograms alone);
//   - "default": what measurement on real frames chose (docs/matching.md gives the numbers).
// The structs' own defaults are the thesis' values; the commands and the daemon start from a preset.
#pragma once

#include <string>
#include <vector>

#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"

namespace toposlam {

struct SimilarityPreset {
  std::string name;
  VpackConfig fingerprint;
  NgramSimilarityConfig similarity;
};

/// "thesis" or "default"; throws std::invalid_argument naming the allowed names otherwise.
SimilarityPreset similarityPreset(const std::string& name);
std::vector<std::string> similarityPresetNames();

}  // namespace toposlam
