// Fingerprint value type: names, validation, equality and the exact binary serialisation.
#include "toposlam/fingerprint/fingerprint.hpp"

#include <algorithm>
#include <array>
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

/// Where a fingerprint is written: a stream, or the end of a byte string (no stream, no copy).
struct StreamSink {
  std::ostream& out;
  void write(const void* data, std::size_t size) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
};
struct StringSink {
  std::string& out;
  void write(const void* data, std::size_t size) { out.append(static_cast<const char*>(data), size); }
};

/// Where a fingerprint is read from. reservable(): how many of `count` elements of `size` bytes can still
/// be there (a stream cannot say: 0, so its containers grow as the data arrives; a corrupt count then
/// fails with "truncated" rather than allocating for what it claims).
struct StreamSource {
  std::istream& in;
  bool read(void* data, std::size_t size) {
    in.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
    return static_cast<bool>(in);
  }
  std::size_t reservable(std::uint32_t, std::size_t) const { return 0; }
};
struct ViewSource {
  std::string_view bytes;
  bool read(void* data, std::size_t size) {
    if (bytes.size() < size) return false;
    std::memcpy(data, bytes.data(), size);
    bytes.remove_prefix(size);
    return true;
  }
  std::size_t reservable(std::uint32_t count, std::size_t size) const {
    return std::min<std::size_t>(count, bytes.size() / size);
  }
};

template <typename Sink, typename T>
void put(Sink& out, const T& v) {
  out.write(&v, sizeof(T));
}

template <typename T, typename Source>
T get(Source& in, const char* what) {
  T v{};
  if (!in.read(&v, sizeof(T))) throw std::runtime_error(std::string("fingerprint data truncated while reading ") + what);
  return v;
}

template <typename Source>
std::uint32_t getCount(Source& in, const char* what) {
  const auto n = get<std::uint32_t>(in, what);
  if (n > kMaxCount) throw std::runtime_error(std::string("fingerprint data corrupt: implausible ") + what);
  return n;
}

template <typename Sink>
void writeTo(Sink& out, const Fingerprint& f) {
  out.write(kMagic, 4);
  put<Sink, std::int32_t>(out, f.image_width);
  put<Sink, std::int32_t>(out, f.image_height);
  put<Sink, std::uint8_t>(out, static_cast<std::uint8_t>(f.backend));
  put<Sink, std::uint32_t>(out, static_cast<std::uint32_t>(f.edge_columns.size()));
  for (int c : f.edge_columns) put<Sink, std::int32_t>(out, c);
  put<Sink, std::uint32_t>(out, static_cast<std::uint32_t>(f.subregions.size()));
  for (const Subregion& s : f.subregions) {
    put<Sink, std::int32_t>(out, s.column_begin);
    put<Sink, std::int32_t>(out, s.column_end);
    put<Sink, std::int32_t>(out, s.keypoint_begin);
    put<Sink, std::int32_t>(out, s.keypoint_end);
    out.write(s.histogram.data(), sizeof(float) * kHistogramBins);
  }
  put<Sink, std::uint32_t>(out, static_cast<std::uint32_t>(f.keypoints.size()));
  for (const cv::KeyPoint& k : f.keypoints) {
    const std::array<float, 5> reals{k.pt.x, k.pt.y, k.size, k.angle, k.response};
    const std::array<std::int32_t, 2> ints{k.octave, k.class_id};
    out.write(reals.data(), sizeof(reals));
    out.write(ints.data(), sizeof(ints));
  }
  put<Sink, std::int32_t>(out, f.descriptors.rows);
  put<Sink, std::int32_t>(out, f.descriptors.cols);
  put<Sink, std::int32_t>(out, f.descriptors.empty() ? 0 : f.descriptors.type());
  for (int r = 0; r < f.descriptors.rows; ++r)
    out.write(f.descriptors.ptr(r), f.descriptors.cols * f.descriptors.elemSize());
}

template <typename Source>
void readEdgesAndSubregions(Source& in, Fingerprint& f) {
  const std::uint32_t edge_count = getCount(in, "edge count");
  f.edge_columns.reserve(in.reservable(edge_count, sizeof(std::int32_t)));
  for (std::uint32_t i = 0; i < edge_count; ++i) f.edge_columns.push_back(get<std::int32_t>(in, "edge column"));
  const std::uint32_t subregion_count = getCount(in, "subregion count");
  f.subregions.reserve(in.reservable(subregion_count, 4 * sizeof(std::int32_t) + sizeof(HclHistogramBins)));
  for (std::uint32_t i = 0; i < subregion_count; ++i) {
    Subregion& s = f.subregions.emplace_back();
    s.column_begin = get<std::int32_t>(in, "subregion");
    s.column_end = get<std::int32_t>(in, "subregion");
    s.keypoint_begin = get<std::int32_t>(in, "subregion");
    s.keypoint_end = get<std::int32_t>(in, "subregion");
    if (!in.read(s.histogram.data(), sizeof(float) * kHistogramBins))
      throw std::runtime_error("fingerprint data truncated while reading a histogram");
  }
}

template <typename Source>
void readKeypointsAndDescriptors(Source& in, Fingerprint& f) {
  const std::uint32_t keypoint_count = getCount(in, "keypoint count");
  f.keypoints.reserve(in.reservable(keypoint_count, 5 * sizeof(float) + 2 * sizeof(std::int32_t)));
  for (std::uint32_t i = 0; i < keypoint_count; ++i) {
    std::array<float, 5> reals{};
    std::array<std::int32_t, 2> ints{};
    if (!in.read(reals.data(), sizeof(reals)) || !in.read(ints.data(), sizeof(ints)))
      throw std::runtime_error("fingerprint data truncated while reading keypoint");
    f.keypoints.emplace_back(cv::Point2f(reals[0], reals[1]), reals[2], reals[3], reals[4], ints[0], ints[1]);
  }
  const auto rows = get<std::int32_t>(in, "descriptor rows");
  const auto cols = get<std::int32_t>(in, "descriptor cols");
  const auto type = get<std::int32_t>(in, "descriptor type");
  if (rows < 0 || cols < 0 || rows > static_cast<std::int32_t>(f.keypoints.size()) || cols > 4096 ||
      (rows > 0 && type != CV_8U && type != CV_32F))
    throw std::runtime_error("fingerprint data corrupt: bad descriptor matrix header");
  if (rows > 0) {
    f.descriptors.create(rows, cols, type);
    if (!in.read(f.descriptors.data, f.descriptors.total() * f.descriptors.elemSize()))
      throw std::runtime_error("fingerprint data truncated while reading descriptors");
  }
}

template <typename Source>
Fingerprint readFrom(Source& in) {
  char magic[4] = {};
  if (!in.read(magic, 4)) throw std::runtime_error("fingerprint data truncated while reading the magic");
  if (std::memcmp(magic, kMagic, 4) != 0) throw std::runtime_error("not a fingerprint (bad magic)");
  Fingerprint f;
  f.image_width = get<std::int32_t>(in, "image width");
  f.image_height = get<std::int32_t>(in, "image height");
  const auto backend = get<std::uint8_t>(in, "backend");
  if (backend > static_cast<std::uint8_t>(KeypointBackend::Akaze))
    throw std::runtime_error("fingerprint data corrupt: unknown keypoint backend");
  f.backend = static_cast<KeypointBackend>(backend);
  readEdgesAndSubregions(in, f);
  readKeypointsAndDescriptors(in, f);
  if (std::string problem = f.validate(); !problem.empty())
    throw std::runtime_error("fingerprint data corrupt: " + problem);
  return f;
}

}  // namespace

void writeFingerprint(std::ostream& out, const Fingerprint& f) {
  StreamSink sink{out};
  writeTo(sink, f);
}

void appendFingerprintBytes(std::string& out, const Fingerprint& f) {
  StringSink sink{out};
  writeTo(sink, f);
}

Fingerprint readFingerprint(std::istream& in) {
  StreamSource source{in};
  return readFrom(source);
}

Fingerprint fingerprintFromBytes(std::string_view bytes) {
  ViewSource source{bytes};
  return readFrom(source);
}

}  // namespace toposlam
