// Fingerprints with real binary descriptors for the tests of the candidate indexes (places and keyframes):
// random 32-byte descriptors drawn from a place's own seed, seen again with some bits flipped.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/fingerprint/fingerprint.hpp"

namespace toposlam::test {

/// `keypoints` random 32-byte descriptors drawn from the place's own seed (the same every time).
inline cv::Mat placeDescriptors(int place, int keypoints) {
  std::mt19937_64 rng(1000003ULL * static_cast<std::uint64_t>(place) + 17);
  cv::Mat d(keypoints, 32, CV_8U);
  for (int r = 0; r < keypoints; ++r)
    for (int c = 0; c < 32; ++c) d.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(rng() & 0xFF);
  return d;
}

/// Flips `bits` distinct random bits of every row (the same keypoint seen again).
inline cv::Mat withNoise(const cv::Mat& d, int bits, std::uint64_t seed) {
  cv::Mat out = d.clone();
  std::mt19937_64 rng(seed);
  for (int r = 0; r < out.rows; ++r) {
    std::vector<int> positions(256);
    for (int i = 0; i < 256; ++i) positions[static_cast<std::size_t>(i)] = i;
    for (int i = 0; i < bits; ++i) {
      const auto j = static_cast<std::size_t>(i) + static_cast<std::size_t>(rng() % static_cast<std::uint64_t>(256 - i));
      std::swap(positions[static_cast<std::size_t>(i)], positions[j]);
      const int bit = positions[static_cast<std::size_t>(i)];
      out.at<std::uint8_t>(r, bit >> 3) = static_cast<std::uint8_t>(out.at<std::uint8_t>(r, bit >> 3) ^ (1u << (bit & 7)));
    }
  }
  return out;
}

/// A valid fingerprint of one subregion holding `descriptors`, tagged `tag` (image width - 1).
inline std::shared_ptr<Fingerprint> fingerprintWith(int tag, const cv::Mat& descriptors,
                                             KeypointBackend backend = KeypointBackend::Orb) {
  auto f = std::make_shared<Fingerprint>();
  f->image_width = tag + 1;
  f->image_height = 1;
  f->backend = backend;
  Subregion whole;
  whole.column_end = tag + 1;
  whole.keypoint_end = descriptors.rows;
  f->subregions.push_back(whole);
  f->keypoints.assign(static_cast<std::size_t>(descriptors.rows), cv::KeyPoint(0.f, 0.f, 1.f));
  f->descriptors = descriptors;
  return f;
}

}  // namespace toposlam::test
