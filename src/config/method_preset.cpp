// Named settings of the whole method: see method_preset.hpp.
#include "toposlam/config/method_preset.hpp"

#include <stdexcept>

#include "toposlam/matching/similarity_preset.hpp"

namespace toposlam {

MethodPreset methodPreset(const std::string& name) {
  const SimilarityPreset similarity = similarityPreset(name);  // throws for unknown names
  MethodPreset p;
  p.name = name;
  p.fingerprint = similarity.fingerprint;
  p.similarity = similarity.similarity;
  if (name == "default") {
    p.segmentation.window_s = 6.0;
    p.segmentation.min_window_frames = 5;
    p.segmentation.min_frame_spacing_m = 0.09;  // with motion and window_m only (docs/segmentation.md)
    p.segmentation.min_frame_spacing_rad = 0.03;
    // Borders at doorways (docs/segmentation.md): simulated office / home boundary F1 at 5 frames 0 / 0
    // without, 0.73 / 0.67 with 7 s; the real frames' places are unchanged (no passage at ~1 Hz).
    // A doorway passage makes a border of its own: office / home F1 0.73 / 0.67 -> 0.77 / 0.87. It made the
    // look-alike rooms keep their wrong closure until a new node got a likelihood floor (below).
    p.segmentation.doorway_shift_s = 7.0;
    p.segmentation.doorway_borders = true;
    // Three other frames of each place besides its representative, for the relative likelihood
    // (docs/topology.md, "Place samples"): one representative per place misses a revisit whose
    // representatives are seconds apart in the room. With the jamb tracks that must keep moving out
    // (DoorwayPassageConfig::min_outward_speed_fraction), office boundary F1 0.77 -> 0.90 and its
    // revisits stay 11 of 12; the real frames' figures are unchanged.
    p.segmentation.place_samples = 3;
    // Seven views of each place besides its representative, kept in the map for the localisation-only
    // mode (docs/daemon.md, "Localisation only"): with the representative alone a frame from another part
    // of the place finds nothing like it. They change no mapping decision. Leave one set out preferred 15
    // by at most 0.01 held out (docs/results.md, "Localisation only"); 7 costs half the memory.
    p.segmentation.place_views = 7;
    p.topology.likelihood = LikelihoodModel::Relative;
    p.topology.relative_slope = 2.0;
    p.topology.relative_offset = 4.25;
    p.topology.relative_sigma_floor = 0.02;
    // A new node's likelihood 1 - max L, without eq. 5.7's entropy: over relative likelihoods it collapses
    // (docs/topology.md, "The new node's likelihood"). Offset 8 -> 4.25 keeps the real samples' closures;
    // the simulated office by day then night closes 11 of 14 revisits instead of 8, 0 wrong.
    p.topology.new_node_entropy = false;
    // "Stay" 0.33 instead of the thesis' 0.05 (gamma(k = 10, theta = 0.25)): a second visit is cut into
    // places where the first was not, so consecutive places on one node are common on real frames
    // (docs/topology.md, "Staying in a node").
    p.topology.gamma_shape = 5.0;
    p.topology.gamma_scale = 0.4;
    // Perceptual aliasing (docs/topology.md, "Look-alike rooms"): a new node keeps at least likelihood
    // 0.01 and a known node leads to a new one with 0.02, so a closure onto a look-alike room leaves the
    // new-node branch enough particles for the places after it to undo it.
    p.topology.new_node_probability = 0.02;
    p.topology.new_node_likelihood_floor = 0.01;
    // The per-frame sequence detector's evidence in the filter's likelihood stays off (weight 0, the key
    // table's default; docs/topology.md, "Sequence evidence in the filter"; docs/results.md): chosen
    // leave-one-set-out over the three real sets and the simulated worlds
    // (docs/results/loso-topology-evidence.sh). At 0.8 the simulated worlds close 734 revisits instead of
    // 648 with 11 wrong instead of 17, but the real building of look-alike floors (tests/data/ie-tower)
    // puts 423 places on another floor's node instead of 322 (filter seeds 1-6), and the real corridor
    // closes none either way.
  }
  if (name == "thesis") {
    p.segmentation.window_s = 0.0;  // n = 25 frames (section 4.2), at the thesis' ~5 fps
    p.segmentation.window = 25;
    p.segmentation.valley = ValleyDetectorConfig{0.5, 0.25};
    p.segmentation.similarity_floor = 0.0;
    p.segmentation.min_keypoints = 15;
    p.segmentation.cut_placement = CutPlacement::ValleyFrame;
    p.segmentation.doorway_shift_s = 0.0;
    p.segmentation.min_frame_spacing_m = 0.0;  // every frame (no motion in the thesis' pipeline)
    p.segmentation.min_frame_spacing_rad = 0.0;
    p.topology.likelihood = LikelihoodModel::Absolute;
    p.topology.particles = 500;
    p.topology.alpha = 15.0;
    p.topology.new_node_probability = 0.05;
    p.topology.gamma_shape = 10.0;
    p.topology.gamma_scale = 0.25;
    p.topology.new_node_entropy = true;
    p.topology.new_node_likelihood_floor = 0.0;
    p.sequence_evidence.frame_revisits = false;  // not in the thesis: no per-frame answer
    p.sequence_evidence.weight = 0.0;            // nor sequence evidence in the filter
  }
  return p;
}

std::vector<std::string> methodPresetNames() { return similarityPresetNames(); }

}  // namespace toposlam
