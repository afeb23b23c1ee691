// Fingerprint value type: names, validation, equality and the exact binary serialisation.
#include "toposlam/fingerprint/fingerprint.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace toposlam {

const char* toString(KeypointBackend backend) {
  switch (backend) {
    case KeypointBackend::Orb: return "orb";
    case KeypointBackend::Sift: return "sift";
    case KeypointBackend::Brisk: return "brisk";
    case KeypointBackend::Akaze: return "akaze";
  }
  return "unknown";
}

KeypointBackend parseKeypointBackend(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "orb") return KeypointBackend::Orb;
  if (lower == "sift") return KeypointBackend::Sift;
  if (lower == "brisk") return KeypointBackend::Brisk;
  if (lower == "akaze") return KeypointBackend::Akaze;
  throw std::invalid_argument("unknown keypoint backend '" + name + "' (allowed: orb, sift, brisk, akaze)");
}

DescriptorKind descriptorKindOf(KeypointBackend backend) {
  return backend == KeypointBackend::Sift ? DescriptorKind::Float : DescriptorKind::Binary;
}

bool Fingerprint::equals(const Fingerprint& other) const {
  if (image_width != other.image_width || image_height != other.image_height || backend != other.backend ||
      edge_columns != other.edge_columns || subregions != other.subregions ||
      keypoints.size() != other.keypoints.size())
    return false;
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const auto& a = keypoints[i];
    const auto& b = other.keypoints[i];
    if (a.pt != b.pt || a.size != b.size || a.angle != b.angle || a.response != b.response ||
        a.octave != b.octave || a.class_id != b.class_id)
      return false;
  }
  if (descriptors.rows != other.descriptors.rows || descriptors.cols != other.descriptors.cols ||
      descriptors.type() != other.descriptors.type())
    return false;
  for (int r = 0; r < descriptors.rows; ++r) {
    const std::size_t bytes = descriptors.cols * descriptors.elemSize();
    if (std::memcmp(descriptors.ptr(r), other.descriptors.ptr(r), bytes) != 0) return false;
  }
  return true;
}

std::string Fingerprint::validate() const {
  std::ostringstream problem;
  if (image_width <= 0 || image_height <= 0) return "image size must be positive";
  if (subregions.size() != edge_columns.size() + 1) {
    problem << subregions.size() << " subregions for " << edge_columns.size() << " edges (expected edges + 1)";
    return problem.str();
  }
  int expected_begin = 0;
  int expected_keypoint = 0;
  for (std::size_t i = 0; i < subregions.size(); ++i) {
    const Subregion& s = subregions[i];
    if (s.column_begin != expected_begin || s.column_end <= s.column_begin || s.column_end > image_width) {
      problem << "subregion " << i << " spans columns [" << s.column_begin << ", " << s.column_end
              << ") which does not continue the previous one inside width " << image_width;
      return problem.str();
    }
    if (i < edge_columns.size() && edge_columns[i] != s.column_end) {
      problem << "subregion " << i << " does not end at edge " << edge_columns[i];
      return problem.str();
    }
    if (s.keypoint_begin != expected_keypoint || s.keypoint_end < s.keypoint_begin) {
      problem << "subregion " << i << " keypoint range is not contiguous";
      return problem.str();
    }
    expected_begin = s.column_end;
    expected_keypoint = s.keypoint_end;
  }
  if (expected_begin != image_width) return "subregions do not cover the image width";
  if (expected_keypoint != keypointCount()) return "subregion keypoint ranges do not cover all keypoints";
  if (!keypoints.empty() && descriptors.rows != keypointCount())
    return "descriptor rows differ from the keypoint count";
  if (!descriptors.empty()) {
    const int expected_type = descriptorKind() == DescriptorKind::Binary ? CV_8U : CV_32F;
    if (descriptors.type() != expected_type) return "descriptor type does not match the keypoint backend";
  }
  return {};
}

// ---------------------------------------------------------------------------------------------------
// Binary format "VPK1": everything little-endian (the build refuses big-endian hosts below).
namespace {

static_assert(std::endian::native == std::endian::little, "serialisation assumes a little-endian host");

constexpr char kMagic[4] = {'V', 'P', 'K', '1'};
constexpr std::uint32_t kMaxCount = 1u << 24;  // sanity bound against garbage lengths

template <typename T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T get(std::istream& in, const char* what) {
  T v{};
  in.read(reinterpret_cast<char*>(&v), sizeof(T));
  if (!in) throw std::runtime_error(std::string("fingerprint data truncated while reading ") + what);
  return v;
}

std::uint32_t getCount(std::istream& in, const char* what) {
  const auto n = get<std::uint32_t>(in, what);
  if (n > kMaxCount) throw std::runtime_error(std::string("fingerprint data corrupt: implausible ") + what);
  return n;
}

}  // namespace

void writeFingerprint(std::ostream& out, const Fingerprint& f) {
  out.write(kMagic, 4);
  put<std::int32_t>(out, f.image_width);
  put<std::int32_t>(out, f.image_height);
  put<std::uint8_t>(out, static_cast<std::uint8_t>(f.backend));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(f.edge_columns.size()));
  for (int c : f.edge_columns) put<std::int32_t>(out, c);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(f.subregions.size()));
  for (const Subregion& s : f.subregions) {
    put<std::int32_t>(out, s.column_begin);
    put<std::int32_t>(out, s.column_end);
    put<std::int32_t>(out, s.keypoint_begin);
    put<std::int32_t>(out, s.keypoint_end);
    out.write(reinterpret_cast<const char*>(s.histogram.data()), sizeof(float) * kHistogramBins);
  }
  put<std::uint32_t>(out, static_cast<std::uint32_t>(f.keypoints.size()));
  for (const cv::KeyPoint& k : f.keypoints) {
    put<float>(out, k.pt.x);
    put<float>(out, k.pt.y);
    put<float>(out, k.size);
    put<float>(out, k.angle);
    put<float>(out, k.response);
    put<std::int32_t>(out, k.octave);
    put<std::int32_t>(out, k.class_id);
  }
  put<std::int32_t>(out, f.descriptors.rows);
  put<std::int32_t>(out, f.descriptors.cols);
  put<std::int32_t>(out, f.descriptors.empty() ? 0 : f.descriptors.type());
  for (int r = 0; r < f.descriptors.rows; ++r)
    out.write(reinterpret_cast<const char*>(f.descriptors.ptr(r)),
              static_cast<std::streamsize>(f.descriptors.cols * f.descriptors.elemSize()));
}

Fingerprint readFingerprint(std::istream& in) {
  char magic[4] = {};
  in.read(magic, 4);
  if (!in) throw std::runtime_error("fingerprint data truncated while reading the magic");
  if (std::memcmp(magic, kMagic, 4) != 0) throw std::runtime_error("not a fingerprint (bad magic)");
  Fingerprint f;
  f.image_width = get<std::int32_t>(in, "image width");
  f.image_height = get<std::int32_t>(in, "image height");
  const auto backend = get<std::uint8_t>(in, "backend");
  if (backend > static_cast<std::uint8_t>(KeypointBackend::Akaze))
    throw std::runtime_error("fingerprint data corrupt: unknown keypoint backend");
  f.backend = static_cast<KeypointBackend>(backend);
  // Containers grow element by element as the data arrives, so a corrupt count fails with
  // "truncated" after reading what is there instead of allocating for the claimed size.
  const std::uint32_t edge_count = getCount(in, "edge count");
  for (std::uint32_t i = 0; i < edge_count; ++i) f.edge_columns.push_back(get<std::int32_t>(in, "edge column"));
  const std::uint32_t subregion_count = getCount(in, "subregion count");
  for (std::uint32_t i = 0; i < subregion_count; ++i) {
    Subregion& s = f.subregions.emplace_back();
    s.column_begin = get<std::int32_t>(in, "subregion");
    s.column_end = get<std::int32_t>(in, "subregion");
    s.keypoint_begin = get<std::int32_t>(in, "subregion");
    s.keypoint_end = get<std::int32_t>(in, "subregion");
    in.read(reinterpret_cast<char*>(s.histogram.data()), sizeof(float) * kHistogramBins);
    if (!in) throw std::runtime_error("fingerprint data truncated while reading a histogram");
  }
  const std::uint32_t keypoint_count = getCount(in, "keypoint count");
  for (std::uint32_t i = 0; i < keypoint_count; ++i) {
    cv::KeyPoint& k = f.keypoints.emplace_back();
    k.pt.x = get<float>(in, "keypoint");
    k.pt.y = get<float>(in, "keypoint");
    k.size = get<float>(in, "keypoint");
    k.angle = get<float>(in, "keypoint");
    k.response = get<float>(in, "keypoint");
    k.octave = get<std::int32_t>(in, "keypoint");
    k.class_id = get<std::int32_t>(in, "keypoint");
  }
  const auto rows = get<std::int32_t>(in, "descriptor rows");
  const auto cols = get<std::int32_t>(in, "descriptor cols");
  const auto type = get<std::int32_t>(in, "descriptor type");
  if (rows < 0 || cols < 0 || rows > static_cast<std::int32_t>(f.keypoints.size()) || cols > 4096 ||
      (rows > 0 && type != CV_8U && type != CV_32F))
    throw std::runtime_error("fingerprint data corrupt: bad descriptor matrix header");
  if (rows > 0) {
    f.descriptors.create(rows, cols, type);
    in.read(reinterpret_cast<char*>(f.descriptors.data),
            static_cast<std::streamsize>(f.descriptors.total() * f.descriptors.elemSize()));
    if (!in) throw std::runtime_error("fingerprint data truncated while reading descriptors");
  }
  if (std::string problem = f.validate(); !problem.empty())
    throw std::runtime_error("fingerprint data corrupt: " + problem);
  return f;
}

}  // namespace toposlam
