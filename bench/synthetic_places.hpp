// Synthetic places made of real fingerprints, for the benchmarks that need maps larger than the bundled
// frames (map-size, revisits): a place's prototype is a sample frame's VPACK fingerprint with its
// descriptor bits scrambled and its colours permuted; an observation of it flips a few bits and replaces a
// share of its keypoints, as seeing the place again does.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "image_input.hpp"
#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"

namespace toposlam::cli {

/// The sample frames' fingerprints (at 320x240) with at least 20 keypoints: what synthetic places are made
/// of. Throws std::runtime_error naming `bench` when there is none.
inline std::vector<Fingerprint> donorFingerprints(const std::string& samples, const VpackConfig& config,
                                                  const std::string& bench) {
  VpackExtractor extractor(config);
  std::vector<Fingerprint> donors;
  for (const cv::Mat& frame : loadSampleFrames(samples, cv::Size(320, 240))) {
    Fingerprint f = extractor.extract(frame);
    if (f.keypointCount() >= 20) donors.push_back(std::move(f));
  }
  if (donors.empty()) throw std::runtime_error("bench " + bench + ": no frame with 20 keypoints in " + samples);
  return donors;
}

inline double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

inline void flipBits(cv::Mat& descriptors, int row, double probability, std::mt19937_64& rng) {
  auto* bytes = descriptors.ptr<std::uint8_t>(row);
  for (int b = 0; b < descriptors.cols * 8; ++b)
    if (uniform(rng) < probability) bytes[b >> 3] = static_cast<std::uint8_t>(bytes[b >> 3] ^ (1u << (b & 7)));
}

/// A new place: the donor's structure, its own keypoints and colours.
inline Fingerprint prototypeOf(const Fingerprint& donor, std::mt19937_64& rng) {
  Fingerprint f = donor;
  f.descriptors = donor.descriptors.clone();
  for (int r = 0; r < f.descriptors.rows; ++r) flipBits(f.descriptors, r, 0.35, rng);
  std::array<int, kHueBins> hue{};
  for (int i = 0; i < kHueBins; ++i) hue[static_cast<std::size_t>(i)] = i;
  for (int i = kHueBins - 1; i > 0; --i) std::swap(hue[static_cast<std::size_t>(i)], hue[static_cast<std::size_t>(rng() % (i + 1))]);
  for (Subregion& s : f.subregions) {
    HclHistogramBins bins = s.histogram;
    for (int i = 0; i < kHueBins; ++i) bins[static_cast<std::size_t>(hue[static_cast<std::size_t>(i)])] = s.histogram[static_cast<std::size_t>(i)];
    s.histogram = bins;
  }
  return f;
}

/// Seeing the place again: a few bits of every keypoint change, 30 % of the keypoints are other ones.
inline std::shared_ptr<const Fingerprint> observationOf(const Fingerprint& prototype, std::mt19937_64& rng) {
  auto f = std::make_shared<Fingerprint>(prototype);
  f->descriptors = prototype.descriptors.clone();
  for (int r = 0; r < f->descriptors.rows; ++r) flipBits(f->descriptors, r, uniform(rng) < 0.3 ? 0.5 : 0.04, rng);
  return f;
}

}  // namespace toposlam::cli
