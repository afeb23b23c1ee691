// MapStore: the map file (map.tsm) that lets a robot stop and go on where it left off.
//
// Layout (little-endian):
//   magic "TSLMAP\r\n" (8 bytes; the CR LF catches text-mode mangling)
//   u32 format version (kMapFormatVersion)   u32 reserved (0)
//   u64 payload size                          u64 checksum of the payload: zlib's CRC-32 from version 3
//                                             (6.5x faster than FNV-1a 64 here; docs/architecture.md),
//                                             FNV-1a 64 in versions 1 and 2 (still read)
//   payload: bytes(filter state, TopologyParticleFilter::saveState) bytes(application data)
//            bytes(settings)                                   (version 2 on; version 1 has none)
//            bytes(views)                                      (version 5 on; earlier ones have none)
// where views = u64 observations, then per observation u32 n and n times bytes(fingerprint): the frames
// of each place kept besides its representative for the localisation-only mode (PlaceViews).
// where bytes(x) = u64 size + x. The application data is opaque to MapStore (the `map` command keeps
// its place/frame bookkeeping there). The settings are "key=value" lines that decide whether a map can
// be continued by a run (the keypoint backend: ORB descriptors mean nothing to a SIFT run; the source,
// kMapSourceKey: a simulated office is no part of the robot's real map; from version 4, every config key
// that changes what the mapping decides, by its path: "segmentation.window=25"); checkSettings() compares
// them. Version 4 differs from 3 only in what the settings hold: a reader of 3 reads it, and a map of
// version 2 or 3 still loads (its settings name the keypoints and the source only).
//
// This header is the format and the policies, with no I/O (an algorithm touches no file): encode()
// and decode() turn a filter into a file image and back; MapFramingCheck verifies a file's framing piece
// by piece; the names below say which files the store keeps beside a map. The file functions of the same
// name space (MapStore::save, load, recover, writeAtomically, removeOrphanedTemporaries, fileVerifies)
// and MapLock carry these policies out through platform/os: toposlam/pipeline/map_files.hpp.
//
// The policies:
// - Writing is atomic (a temporary file ".<name>.XXXXXX" in the same directory, fsync'ed, renamed over
//   the target, the directory fsync'ed). The file it replaces is first renamed to "<path>.prev", but only
//   when that file verifies (framing and checksum), so saving over a damaged map never pushes the last
//   good one out of .prev. At every instant <path> or <path>.prev is a complete map, and the two are
//   never one file; between the two renames <path> is missing and recovery loads <path>.prev.
// - Recovery tries the map, then its .prev (recoveryCandidates); a file that does not load is moved
//   aside under a timestamped name (<path>.damaged-YYYYmmddTHHMMSS[-N]; never over an earlier one) and
//   the oldest damaged copies beyond kMaxDamagedFiles are removed.
// - The temporaries a kill -9 during a save leaves behind are recognised by their names
//   (isTemporaryOf) and removed at the next start, under the map's lock.
// Loading refuses a wrong magic, a newer version, a truncated or damaged file with a MapStoreError that
// says which.
//
// Thread-safety: the functions are reentrant; MapFramingCheck is one reader's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

inline constexpr std::uint32_t kMapFormatVersion = 5;

/// Per filter observation, the place's views (ClosedPlace::views; may be empty): no decision reads them.
using PlaceViews = std::vector<std::vector<std::shared_ptr<const Fingerprint>>>;
/// Default cap on a map file's size (bytes): a bigger file is refused before it is read. A map of 100
/// places with 500 particles is about 1 MB.
inline constexpr std::uint64_t kDefaultMaxMapBytes = 256ull << 20;
/// Damaged files kept aside per map (the oldest beyond this are removed).
inline constexpr int kMaxDamagedFiles = 5;

/// "key" -> "value" settings a map was made with (see checkSettings).
using MapSettings = std::map<std::string, std::string>;

struct VpackConfig;
/// The fingerprint settings a map must be continued with: the keypoint backend ("keypoints").
MapSettings fingerprintMapSettings(const VpackConfig& config);
/// The setting naming the source a map was made from (io/source_uri.hpp, sourceIdentity: "sim:office",
/// "v4l2:/dev/video0"). A run from another source continues the map only when told to explicitly.
inline constexpr const char* kMapSourceKey = "source";
/// Where the map's source stands: the sequence number and name of the last frame the map holds (the last
/// frame of its last place). Recorded for sources that name their frames (images:), so that a restart
/// continues after it instead of mapping the same frames again (FrameSource::continueAfter). Not compared by
/// checkSettings (a run's own settings have no such keys).
inline constexpr const char* kMapSourceLastFrameKey = "source.last_frame";
inline constexpr const char* kMapSourceLastFrameNameKey = "source.last_frame_name";
/// True when both settings have `key` and its values differ (what checkSettings would name for it).
bool settingDiffers(const MapSettings& recorded, const MapSettings& current, const std::string& key);

class MapStoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A map file over the size cap (refused from its size, unread). Not damage: recover() does not move it.
class MapTooLargeError : public MapStoreError {
 public:
  using MapStoreError::MapStoreError;
};

/// FNV-1a, 64 bit.
std::uint64_t fnv1a64(std::string_view data);
/// The payload checksum a map file of format `version` carries (CRC-32 from 3, FNV-1a 64 before).
std::uint64_t mapPayloadChecksum(std::uint32_t version, std::string_view payload);

struct LoadedMap {
  std::unique_ptr<TopologyParticleFilter> filter;
  std::string application_data;
  MapSettings settings;  ///< empty for a version-1 file (recorded nothing)
  PlaceViews views;      ///< one entry per observation (all empty before version 5)
};

/// The fixed header in front of the payload: magic, version, reserved, payload size, checksum (bytes).
inline constexpr std::size_t kMapHeaderSize = 8 + 4 + 4 + 8 + 8;

/// Checks a map file's framing (magic, version, size, checksum) from its bytes fed in order, without
/// holding the file: start() with the first kMapHeaderSize bytes, add() the payload in pieces, then
/// verified(). The payload itself is not parsed.
class MapFramingCheck {
 public:
  /// False when `header` is not the header of a map this build reads whose payload makes the file
  /// exactly `file_size` bytes long (then there is nothing to add).
  bool start(std::string_view header, std::uint64_t file_size);
  /// The payload's size in bytes, after start() returned true.
  std::uint64_t payloadSize() const { return payload_size_; }
  void add(const char* data, std::size_t size);
  /// True when the payload added has the checksum the header records.
  bool verified() const;

 private:
  std::uint32_t version_ = 0;
  std::uint64_t payload_size_ = 0;
  std::uint64_t expected_ = 0;
  bool crc_ = false;
  std::uint64_t crc32_ = 0;
  std::uint64_t fnv_ = 0;
};

/// The format, and the names of the files kept beside a map (see the policies above). The file functions
/// of this name space are in toposlam/pipeline/map_files.hpp.
namespace MapStore {

/// The whole file image of `filter` (+ application data). Throws std::logic_error during a step.
std::string encode(const TopologyParticleFilter& filter, std::string_view application_data = {},
                   const MapSettings& settings = {}, const PlaceViews& views = {});
/// The file image of a frozen state (TopologyParticleFilter::freeze()): what encode(filter) gave when
/// it was frozen. Any thread (see FrozenTopologyState).
std::string encode(const FrozenTopologyState& state, std::string_view application_data = {},
                   const MapSettings& settings = {}, const PlaceViews& views = {});
/// Parses a file image; `name` is used in error messages. Throws MapStoreError.
LoadedMap decode(std::string_view file, const SimilarityMeasure& similarity, const std::string& name = "map");

/// Empty when a map recorded with `recorded` settings can be continued by a run with `current` ones
/// (keys present in both agree; a version-1 map recorded none), else a message naming both values.
std::string checkSettings(const MapSettings& recorded, const MapSettings& current, const std::string& name);

/// What a save writes its temporary file under: "." + the map's name + this + six characters.
inline constexpr const char* kTemporaryInfix = ".";
/// "<path>.prev": the map a save replaced, when it verified.
std::filesystem::path previousPath(const std::filesystem::path& path);
/// The name a start-up probe (checkWritable) renames its temporary file to: the temporary's name +
/// ".probe" (so that a kill -9 leaves only names isTemporaryOf recognises).
std::string probePath(const std::string& temporary_path);
/// The files recovery tries, newest first: the map, then its .prev.
std::vector<std::filesystem::path> recoveryCandidates(const std::filesystem::path& path);
/// True when `file_name` (a bare name in the map's directory) is the temporary file of a save of `path`
/// (".<name>.XXXXXX", ".<name>.XXXXXX.probe", or ".<name>.XXXXXX.prev", the link older builds made;
/// six letters or digits).
bool isTemporaryOf(const std::filesystem::path& path, const std::string& file_name);
/// Where a damaged `file` is moved: "<file>.damaged-<timestamp>", or "...-<attempt>" for attempt >= 1
/// (when the earlier names are taken).
std::filesystem::path damagedPath(const std::filesystem::path& file, const std::string& timestamp, int attempt);
/// True when `file_name` (a bare name in the directory of `file`) is a damaged copy of `file`.
bool isDamagedCopyOf(const std::filesystem::path& file, const std::string& file_name);
/// Of the damaged copies of one file, those to remove (oldest first) so that kMaxDamagedFiles remain.
std::vector<std::filesystem::path> damagedCopiesToRemove(std::vector<std::filesystem::path> copies);

}  // namespace MapStore

}  // namespace toposlam
