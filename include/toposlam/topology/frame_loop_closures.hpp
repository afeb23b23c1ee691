// Frame-level loop closures, the way the loop-closure literature scores them (docs/topology.md, "Frame
// level"): every frame whose place the most probable topology puts on a node seen on an earlier visit
// gets, as its detection, the most similar frame of those earlier visits and of the places just before
// and after each of them (a place border falls a little differently on each visit), scored by the
// similarity times the place's node probability. A visit of a node is a maximal run of consecutive
// places on it; frames of the same visit are never a detection (the robot never left), nor are frames
// fewer than min_gap back or with similarity 0.
//
// Pure: inputs are plain vectors and the similarity measure. Thread-safe if the measure is.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/matching/similarity_measure.hpp"

namespace toposlam {

struct FrameMatch {
  std::int64_t match_frame = -1;  ///< the detected earlier frame, -1: no detection
  double similarity = 0.0;        ///< symmetric similarity with it
  double score = 0.0;             ///< similarity x node probability of the frame's place
};

/// place_of_frame[f]: kept place of frame f (-1: none); node_of_place[p], probability_of_place[p]: its
/// node in the most probable topology and that node's probability; fingerprints[f] may be null (frame
/// not kept: never a candidate). Places are in time order. Returns one FrameMatch per frame.
std::vector<FrameMatch> matchFramesToEarlierVisits(const std::vector<std::int64_t>& place_of_frame,
                                                   const std::vector<std::int64_t>& node_of_place,
                                                   const std::vector<double>& probability_of_place,
                                                   const std::vector<std::shared_ptr<const Fingerprint>>& fingerprints,
                                                   const SimilarityMeasure& similarity, int min_gap);

}  // namespace toposlam
