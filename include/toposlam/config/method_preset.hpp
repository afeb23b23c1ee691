// Named settings of the whole method, every stage at once (docs/architecture.md, "Presets"):
//   - "default": what measurement on real frames chose (docs/matching.md, docs/segmentation.md,
//     docs/topology.md give the numbers);
//   - "thesis": the method exactly as published (chapters 3-5): 100 keypoints, the n-gram similarity
//     with histograms and keypoints weighted equally, a 25-frame window with gamma 0.5 and delta 0.25
//     and the place ending at the valley frame (Algorithm 4.1), the similarity itself as the filter's
//     likelihood (eq. 5.5).
// A preset sets defaults; any key or option given explicitly overrides it. The stage structs' own
// defaults (used by the algorithm classes' tests) are neither: the daemon and the commands start from a
// preset, "default" unless told otherwise.
#pragma once

#include <string>
#include <vector>

#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

struct MethodPreset {
  std::string name;
  VpackConfig fingerprint;
  NgramSimilarityConfig similarity;
  FiedlerSegmenterConfig segmentation;
  TopologyFilterConfig topology;
  /// The sequence detector: its per-frame answer (on in "default", off in "thesis") and its evidence.
  SequenceEvidenceConfig sequence_evidence;
};

/// "default" or "thesis"; throws std::invalid_argument naming the allowed names otherwise.
MethodPreset methodPreset(const std::string& name);
std::vector<std::string> methodPresetNames();

}  // namespace toposlam
