// StageAssembly: the stages built from their settings, in dependency order; see stage_assembly.hpp.
#include "toposlam/pipeline/stage_assembly.hpp"

namespace toposlam {

namespace {
/// The segmentation stage keeps the thumbnails of this many frames for the place events.
constexpr std::size_t kKeptThumbnails = 600;
}  // namespace

NodeLocalizerConfig nodeLocalizerConfig(const NgramSimilarityConfig& similarity, const MapLocalizeConfig& localize) {
  NodeLocalizerConfig c;
  c.localizer.similarity = similarity;
  c.min_probability = localize.min_probability;
  c.jump_weight = localize.jump_weight;
  return c;
}

StageAssembly::StageAssembly(const StageSettings& settings, const Clock& clock, WorkerPool* pool,
                             Thumbnails thumbnails) {
  const bool kept = thumbnails == Thumbnails::Kept;
  fingerprint_ = std::make_unique<VpackFingerprintStage>(
      settings.fingerprint, pool, kept ? settings.fingerprint_stage.thumbnail_width : VpackFingerprintStage::kNoThumbnail);
  similarity_ = std::make_unique<NgramSimilarity>(settings.similarity);
  segmentation_ = std::make_unique<FiedlerSegmentationStage>(settings.segmentation, *similarity_,
                                                             kept ? kKeptThumbnails : 1,
                                                             settings.segmentation_stage.motion,
                                                             settings.sequence_evidence);
  topology_ = std::make_unique<ParticleFilterTopologyStage>(settings.topology, *similarity_, clock,
                                                            settings.topology_stage);
}

}  // namespace toposlam
