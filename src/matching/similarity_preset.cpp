// Named settings of the fingerprint and the similarity: see similarity_preset.hpp.
#include "toposlam/matching/similarity_preset.hpp"

#include <stdexcept>

namespace toposlam {

SimilarityPreset similarityPreset(const std::string& name) {
  SimilarityPreset p;
  p.name = name;
  if (name == "default") {
    p.similarity.keypoint_scoring = KeypointScoring::VerifiedMatches;
    p.similarity.histogram_only_fallback = false;
    p.similarity.histogram_weight = 0.05;
    p.similarity.matcher.ratio_test = 0.8;
    p.similarity.matcher.mutual_check = true;
    p.similarity.matcher.max_angle_difference_deg = 25.0;
    p.fingerprint.keypoints.orb_levels = 6;
    return p;
  }
  if (name == "thesis") {
    p.fingerprint.keypoints.max_keypoints = 100;
    p.similarity.histogram_weight = 0.5;
    p.similarity.keypoint_scoring = KeypointScoring::PossibleNgrams;
    p.similarity.histogram_only_fallback = true;
    p.similarity.matcher.max_hellinger_distance = 0.3;
    p.similarity.matcher.max_binary_distance_fraction = 0.25;
    p.similarity.matcher.ratio_test = 0.9;
    p.similarity.matcher.mutual_check = false;
    p.similarity.matcher.max_angle_difference_deg = 0.0;
    p.fingerprint.keypoints.orb_levels = 4;
    return p;
  }
  throw std::invalid_argument("preset '" + name + "': expected one of default, thesis");
}

std::vector<std::string> similarityPresetNames() { return {"default", "thesis"}; }

}  // namespace toposlam
