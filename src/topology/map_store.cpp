// MapStore's format: framing (magic, version, size, checksum), the payload, the settings, and the names
// of the files kept beside a map. No I/O here: the file functions are in src/pipeline/map_files.cpp.
#include "toposlam/topology/map_store.hpp"

#include <algorithm>
#include <cstring>
#include <vector>
#include <zlib.h>

#include "binary_io.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"

namespace toposlam {

namespace {

constexpr char kMagic[8] = {'T', 'S', 'L', 'M', 'A', 'P', '\r', '\n'};
constexpr std::size_t kHeaderSize = kMapHeaderSize;
constexpr std::uint64_t kFnvOffset = 0xcbf29ce484222325ULL;

std::string settingsText(const MapSettings& settings) {
  std::string text;
  for (const auto& [key, value] : settings) text += key + "=" + value + "\n";
  return text;
}

MapSettings parseSettings(std::string_view text, const std::string& name) {
  MapSettings settings;
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    if (end == std::string_view::npos) throw MapStoreError(name + ": damaged map file (unterminated setting)");
    const std::string_view line = text.substr(0, end);
    text.remove_prefix(end + 1);
    const std::size_t eq = line.find('=');
    if (eq == std::string_view::npos || eq == 0)
      throw MapStoreError(name + ": damaged map file (bad setting line)");
    settings[std::string(line.substr(0, eq))] = std::string(line.substr(eq + 1));
  }
  return settings;
}

}  // namespace

std::uint64_t fnv1a64(std::string_view data) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (char c : data) {
    hash ^= static_cast<std::uint8_t>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

namespace {

/// zlib's CRC-32 of `data` continued from `crc`.
std::uint64_t addCrc32(std::uint64_t crc, const char* data, std::size_t size) {
  uLong value = static_cast<uLong>(crc);
  // zlib takes at most a uInt per call.
  while (size > 0) {
    const auto n = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    value = ::crc32(value, reinterpret_cast<const Bytef*>(data), n);
    data += n;
    size -= n;
  }
  return static_cast<std::uint64_t>(value);
}

/// FNV-1a 64 of `data` continued from `hash`.
std::uint64_t addFnv1a64(std::uint64_t hash, const char* data, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<std::uint8_t>(data[i]);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

/// The checksum a map file of format `version` carries: CRC-32 from version 3, FNV-1a 64 before.
bool usesCrc32(std::uint32_t version) { return version >= 3; }

}  // namespace

std::uint64_t mapPayloadChecksum(std::uint32_t version, std::string_view payload) {
  return usesCrc32(version) ? addCrc32(::crc32(0L, Z_NULL, 0), payload.data(), payload.size())
                            : addFnv1a64(kFnvOffset, payload.data(), payload.size());
}

bool settingDiffers(const MapSettings& recorded, const MapSettings& current, const std::string& key) {
  const auto a = recorded.find(key);
  const auto b = current.find(key);
  return a != recorded.end() && b != current.end() && a->second != b->second;
}

MapSettings fingerprintMapSettings(const VpackConfig& config) {
  return MapSettings{{"keypoints", toString(config.keypoints.backend)}};
}

namespace {

/// The views section: one entry per observation (missing ones empty, extra ones left out).
void appendViews(std::string& out, const PlaceViews& views, int observations) {
  topology_detail::BinaryWriter w(std::move(out));
  w.u64(static_cast<std::uint64_t>(observations));
  for (int o = 0; o < observations; ++o) {
    const auto k = static_cast<std::size_t>(o);
    std::uint32_t n = 0;
    if (k < views.size())
      for (const auto& v : views[k]) n += v ? 1u : 0u;
    w.u32(n);
    if (k >= views.size()) continue;
    for (const auto& v : views[k])
      if (v) w.bytesFrom([&](std::string& bytes) { appendFingerprintBytes(bytes, *v); });
  }
  out = w.take();
}

PlaceViews readViews(std::string_view section, int observations) {
  topology_detail::BinaryReader r(section);
  const std::uint64_t count = r.u64("view count");
  if (count != static_cast<std::uint64_t>(observations))
    throw std::runtime_error("the views are of " + std::to_string(count) + " places, the filter has " +
                             std::to_string(observations));
  PlaceViews views(static_cast<std::size_t>(observations));
  for (auto& place : views) {
    const std::uint32_t n = r.u32("views of a place");
    if (n > 1024) throw std::runtime_error("a place has " + std::to_string(n) + " views");
    for (std::uint32_t i = 0; i < n; ++i) {
      auto view = std::make_shared<Fingerprint>(fingerprintFromBytes(r.bytes("view")));
      if (const std::string problem = view->validate(); !problem.empty())
        throw std::runtime_error("an invalid view: " + problem);
      place.push_back(std::move(view));
    }
  }
  if (!r.atEnd()) throw std::runtime_error("trailing bytes in the views");
  return views;
}

}  // namespace

std::string MapStore::encode(const TopologyParticleFilter& filter, std::string_view application_data,
                             const MapSettings& settings, const PlaceViews& views) {
  return encode(filter.freeze(), application_data, settings, views);
}

std::string MapStore::encode(const FrozenTopologyState& frozen, std::string_view application_data,
                             const MapSettings& settings, const PlaceViews& views) {
  // One buffer: the header with room for the size and checksum, the payload after it (the state written
  // in place), then the two fields filled in. No copy of the payload, which is ~5 KB per stored place.
  topology_detail::BinaryWriter file;
  for (char c : kMagic) file.u8(static_cast<std::uint8_t>(c));
  file.u32(kMapFormatVersion);
  file.u32(0);
  file.u64(0);  // payload size, below
  file.u64(0);  // checksum, below
  file.bytesFrom([&](std::string& out) { frozen.appendState(out); });
  file.bytes(application_data);
  file.bytes(settingsText(settings));
  file.bytesFrom([&](std::string& out) { appendViews(out, views, frozen.observationCount()); });
  std::string out = file.take();
  const std::string_view payload = std::string_view(out).substr(kHeaderSize);
  const std::uint64_t checksum = mapPayloadChecksum(kMapFormatVersion, payload);
  topology_detail::BinaryWriter fields;
  fields.u64(payload.size());
  fields.u64(checksum);
  out.replace(kHeaderSize - 16, 16, fields.data());
  return out;
}

namespace {

/// The payload of a file image whose framing verifies. Throws MapStoreError saying what is wrong.
std::string_view verifiedPayload(std::string_view file, const std::string& name) {
  if (file.size() < 8 || std::memcmp(file.data(), kMagic, 8) != 0) {
    throw MapStoreError(name + ": not a toposlam map file (bad magic)");
  }
  if (file.size() < kHeaderSize) throw MapStoreError(name + ": truncated map file (incomplete header)");
  topology_detail::BinaryReader header(file.substr(8, kHeaderSize - 8));
  const std::uint32_t version = header.u32("version");
  header.u32("reserved");
  const std::uint64_t size = header.u64("size");
  const std::uint64_t checksum = header.u64("checksum");
  if (version > kMapFormatVersion) {
    throw MapStoreError(name + ": map format version " + std::to_string(version) +
                        " was written by a newer toposlam; this build reads up to version " +
                        std::to_string(kMapFormatVersion));
  }
  if (version == 0) throw MapStoreError(name + ": bad map format version 0");
  const std::string_view payload = file.substr(kHeaderSize);
  if (payload.size() < size) {
    throw MapStoreError(name + ": truncated map file (" + std::to_string(payload.size()) + " of " +
                        std::to_string(size) + " payload bytes)");
  }
  if (payload.size() > size)
    throw MapStoreError(name + ": damaged map file (trailing bytes after the payload)");
  if (mapPayloadChecksum(version, payload) != checksum) throw MapStoreError(name + ": damaged map file (checksum mismatch)");
  return payload;
}

}  // namespace

LoadedMap MapStore::decode(std::string_view file, const SimilarityMeasure& similarity, const std::string& name) {
  const std::string_view payload = verifiedPayload(file, name);
  const std::uint32_t version = topology_detail::BinaryReader(file.substr(8, 4)).u32("version");
  try {
    topology_detail::BinaryReader reader(payload);
    const std::string_view state = reader.bytes("filter state");
    LoadedMap loaded;
    loaded.application_data = std::string(reader.bytes("application data"));
    if (version >= 2) loaded.settings = parseSettings(reader.bytes("settings"), name);
    const std::string_view views = version >= 5 ? reader.bytes("views") : std::string_view();
    if (!reader.atEnd()) throw std::runtime_error("trailing bytes in the payload");
    loaded.filter = TopologyParticleFilter::loadState(state, similarity);
    const int observations = loaded.filter->observationCount();
    loaded.views = version >= 5 ? readViews(views, observations) : PlaceViews(static_cast<std::size_t>(observations));
    return loaded;
  } catch (const MapStoreError&) {
    throw;
  } catch (const std::exception& e) {
    throw MapStoreError(name + ": damaged map file (" + e.what() + ")");
  }
}

bool MapFramingCheck::start(std::string_view header, std::uint64_t file_size) {
  if (header.size() < kHeaderSize || file_size < kHeaderSize) return false;
  if (std::memcmp(header.data(), kMagic, 8) != 0) return false;
  topology_detail::BinaryReader fields(header.substr(8, kHeaderSize - 8));
  version_ = fields.u32("version");
  fields.u32("reserved");
  payload_size_ = fields.u64("size");
  expected_ = fields.u64("checksum");
  if (version_ == 0 || version_ > kMapFormatVersion || file_size - kHeaderSize != payload_size_) return false;
  crc_ = usesCrc32(version_);
  crc32_ = ::crc32(0L, Z_NULL, 0);
  fnv_ = kFnvOffset;
  return true;
}

void MapFramingCheck::add(const char* data, std::size_t size) {
  if (crc_)
    crc32_ = addCrc32(crc32_, data, size);
  else
    fnv_ = addFnv1a64(fnv_, data, size);
}

bool MapFramingCheck::verified() const { return (crc_ ? crc32_ : fnv_) == expected_; }

std::string MapStore::checkSettings(const MapSettings& recorded, const MapSettings& current,
                                    const std::string& name) {
  std::string recorded_text, current_text;
  for (const auto& [key, value] : recorded) {
    const auto found = current.find(key);
    if (found == current.end() || found->second == value) continue;
    recorded_text += (recorded_text.empty() ? "" : ", ") + key + "=" + value;
    current_text += (current_text.empty() ? "" : ", ") + key + "=" + found->second;
  }
  if (recorded_text.empty()) return {};
  return "the map " + name + " was made with " + recorded_text + " but this run uses " + current_text +
         ": continue it with the same settings, or start a new map";
}

// ------------------------------------------------------------------------------------------------------------
// The names of the files kept beside a map.

std::filesystem::path MapStore::previousPath(const std::filesystem::path& path) { return path.string() + ".prev"; }

std::string MapStore::probePath(const std::string& temporary_path) { return temporary_path + ".probe"; }

std::vector<std::filesystem::path> MapStore::recoveryCandidates(const std::filesystem::path& path) {
  return {path, previousPath(path)};
}

bool MapStore::isTemporaryOf(const std::filesystem::path& path, const std::string& file_name) {
  std::string prefix = ".";  // built piecewise: GCC 12 warns falsely (-Wrestrict) on "." + string
  prefix += path.filename().string();
  prefix += kTemporaryInfix;
  if (file_name.rfind(prefix, 0) != 0) return false;
  std::string rest = file_name.substr(prefix.size());
  if (rest.size() == 6 + 5 && rest.compare(6, 5, ".prev") == 0) rest.resize(6);  // an older build's link
  if (rest.size() == 6 + 6 && rest.compare(6, 6, ".probe") == 0) rest.resize(6);
  // mkstemp's six characters: letters and digits.
  return rest.size() == 6 && std::all_of(rest.begin(), rest.end(), [](char c) {
           return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
         });
}

std::filesystem::path MapStore::damagedPath(const std::filesystem::path& file, const std::string& timestamp,
                                            int attempt) {
  std::string name = file.string() + ".damaged-" + timestamp;
  if (attempt >= 1) {
    name += '-';  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "-" + string
    name += std::to_string(attempt);
  }
  return name;
}

bool MapStore::isDamagedCopyOf(const std::filesystem::path& file, const std::string& file_name) {
  return file_name.rfind(file.filename().string() + ".damaged-", 0) == 0;
}

std::vector<std::filesystem::path> MapStore::damagedCopiesToRemove(std::vector<std::filesystem::path> copies) {
  std::sort(copies.begin(), copies.end());  // oldest first: "<ts>" < "<ts>-1" < "<later ts>"
  const std::size_t keep = static_cast<std::size_t>(kMaxDamagedFiles);
  if (copies.size() <= keep) return {};
  copies.resize(copies.size() - keep);
  return copies;
}

}  // namespace toposlam
