// The VPACK fingerprint of one frame (thesis chapter 3.2.4): ordered subregions between structural
// vertical edges, each with a 13-bin HCL colour histogram and a few keypoints.
//
// A plain value type. All keypoints of the frame live in one contiguous descriptor matrix, grouped by
// subregion (subregion i owns rows [keypoint_begin, keypoint_end)), so matching can scan them without
// chasing pointers. Serialisation is exact (bit-for-bit round trip).
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

namespace toposlam {

/// Number of bins of the HCL histogram: 8 circular hue bins followed by 5 grey bins.
inline constexpr int kHueBins = 8;
inline constexpr int kGreyBins = 5;
inline constexpr int kHistogramBins = kHueBins + kGreyBins;

/// 13-bin HCL histogram. Bins 0..7: hue centred on 0, 45, ..., 315 degrees (0 = red, 2 = 90 deg
/// yellow-green, 4 = cyan, ...). Bins 8..12: grey levels white, light, medium, dark, black.
/// Sums to 1 when the subregion had at least one counted pixel, else all zero.
using HclHistogramBins = std::array<float, kHistogramBins>;

enum class KeypointBackend : std::uint8_t { Orb = 0, Sift = 1, Brisk = 2, Akaze = 3 };

/// Binary descriptors (ORB, BRISK, AKAZE-MLDB) compare by Hamming distance, float ones (SIFT) by L2.
enum class DescriptorKind : std::uint8_t { Binary = 0, Float = 1 };

const char* toString(KeypointBackend backend);
/// Parses "orb", "sift", "brisk", "akaze" (case-insensitive); throws std::invalid_argument otherwise.
KeypointBackend parseKeypointBackend(const std::string& name);
DescriptorKind descriptorKindOf(KeypointBackend backend);

/// One "letter": the image columns [column_begin, column_end) between two vertical edges.
struct Subregion {
  int column_begin = 0;
  int column_end = 0;
  HclHistogramBins histogram{};
  int keypoint_begin = 0;  ///< first row of Fingerprint::descriptors owned by this subregion
  int keypoint_end = 0;    ///< one past the last row

  int width() const { return column_end - column_begin; }
  int keypointCount() const { return keypoint_end - keypoint_begin; }
  bool operator==(const Subregion&) const = default;
};

struct Fingerprint {
  int image_width = 0;   ///< pixels
  int image_height = 0;  ///< pixels
  KeypointBackend backend = KeypointBackend::Orb;
  std::vector<int> edge_columns;       ///< detected vertical edges, ascending, in pixels
  std::vector<Subregion> subregions;   ///< edge_columns.size() + 1 subregions, left to right
  std::vector<cv::KeyPoint> keypoints; ///< all keypoints, grouped by subregion, full-image coordinates
  cv::Mat descriptors;                 ///< one row per keypoint: CV_8U (binary) or CV_32F (float)

  DescriptorKind descriptorKind() const { return descriptorKindOf(backend); }
  int keypointCount() const { return static_cast<int>(keypoints.size()); }
  /// Exact equality, including every descriptor byte (used by round-trip tests and map loading).
  bool equals(const Fingerprint& other) const;
  /// Checks internal consistency (ordered, contiguous subregions; ranges inside the descriptor
  /// matrix). Returns an empty string when valid, else a description of the first problem.
  std::string validate() const;
};

/// Binary serialisation, little-endian, versioned ("VPK1"). write() never fails on a good stream;
/// read() throws std::runtime_error with a precise message on truncated or malformed data.
void writeFingerprint(std::ostream& out, const Fingerprint& fingerprint);
Fingerprint readFingerprint(std::istream& in);
/// The same bytes as writeFingerprint, appended to `out` (no stream: what a map save writes per place).
void appendFingerprintBytes(std::string& out, const Fingerprint& fingerprint);
/// readFingerprint of the bytes at the start of `bytes` (no stream, no copy: what a map load reads per
/// place); the same checks and messages. Bytes after the fingerprint are ignored.
Fingerprint fingerprintFromBytes(std::string_view bytes);

}  // namespace toposlam
