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
// where bytes(x) = u64 size + x. The application data is opaque to MapStore (the `map` command keeps
// its place/frame bookkeeping there). The settings are "key=value" lines that decide whether a map can
// be continued by a run (the keypoint backend: ORB descriptors mean nothing to a SIFT run; the source,
// kMapSourceKey: a simulated office is no part of the robot's real map); checkSettings() compares them.
//
// Writing is atomic: a temporary file in the same directory is written, fsync'ed, renamed over the
// target, and the directory is fsync'ed. The file it replaces is kept as "<path>.prev" (a hard link),
// but only when that file verifies (framing and checksum), so saving over a damaged map never pushes
// the last good one out of .prev.
// Any failure (e.g. a full disk) throws MapStoreError and leaves the old file untouched.
// Loading refuses a wrong magic, a newer version, a truncated or damaged file with a MapStoreError that
// says which; the file on disk is never modified by loading. A file larger than the size cap is refused
// from its size before anything is read; a file is read once, into one buffer.
//
// Recovery (recover(), for the daemon's start): a map that does not load is moved aside under a
// timestamped name (<path>.damaged-YYYYmmddTHHMMSS[-N]; never over an earlier one; the oldest beyond
// kMaxDamagedFiles are removed) and the newest file that loads, <path>.prev, is used instead.
// MapLock (flock on <path>.lock) keeps a second writer off a map; removeOrphanedTemporaries() deletes
// the temporary files a kill -9 during a save leaves behind (call it while holding the lock).
//
// Thread-safety: the functions are reentrant; do not save to the same path from two threads.
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

inline constexpr std::uint32_t kMapFormatVersion = 3;
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

/// The system calls MapStore writes through; tests inject failures (a full disk) by overriding them.
class MapFileOps {
 public:
  virtual ~MapFileOps() = default;
  /// Like ::write: bytes written, or -1 with errno set.
  virtual long write(int fd, const void* data, std::size_t size) const;
  /// Like ::fsync: 0, or -1 with errno set.
  virtual int fsync(int fd) const;
};

/// FNV-1a, 64 bit.
std::uint64_t fnv1a64(std::string_view data);
/// The payload checksum a map file of format `version` carries (CRC-32 from 3, FNV-1a 64 before).
std::uint64_t mapPayloadChecksum(std::uint32_t version, std::string_view payload);

struct LoadedMap {
  std::unique_ptr<TopologyParticleFilter> filter;
  std::string application_data;
  MapSettings settings;  ///< empty for a version-1 file (recorded nothing)
};

/// What MapStore::recover found.
struct RecoveredMap {
  std::optional<LoadedMap> map;         ///< empty: no file loaded (start a new map)
  std::filesystem::path loaded_from;    ///< the file `map` came from (the map or its .prev)
  std::vector<std::string> problems;    ///< one line per file that did not load and what became of it
};

/// An exclusive advisory lock (flock) on a map, held while the object lives. Movable.
class MapLock {
 public:
  /// Locks `map_path` through "<map_path>.lock" (created if needed; when the directory is read-only,
  /// the directory itself is locked). Throws MapStoreError naming the file when another process holds
  /// it (with that process' id when known).
  static MapLock acquire(const std::filesystem::path& map_path);
  MapLock(MapLock&& other) noexcept;
  MapLock& operator=(MapLock&& other) noexcept;
  MapLock(const MapLock&) = delete;
  MapLock& operator=(const MapLock&) = delete;
  ~MapLock();
  /// The file (or directory) locked.
  const std::filesystem::path& lockedPath() const { return locked_; }

 private:
  MapLock(int fd, std::filesystem::path locked) : fd_(fd), locked_(std::move(locked)) {}
  int fd_ = -1;
  std::filesystem::path locked_;
};

class MapStore {
 public:
  /// The whole file image of `filter` (+ application data). Throws std::logic_error during a step.
  static std::string encode(const TopologyParticleFilter& filter, std::string_view application_data = {},
                            const MapSettings& settings = {});
  /// The file image of a frozen state (TopologyParticleFilter::freeze()): what encode(filter) gave when
  /// it was frozen. Any thread (see FrozenTopologyState).
  static std::string encode(const FrozenTopologyState& state, std::string_view application_data = {},
                            const MapSettings& settings = {});
  /// Parses a file image; `name` is used in error messages. Throws MapStoreError.
  static LoadedMap decode(std::string_view file, const SimilarityMeasure& similarity,
                          const std::string& name = "map");

  /// Atomically replaces `path` (see above). Throws MapStoreError.
  static void save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
                   std::string_view application_data = {}, const MapFileOps& ops = MapFileOps{});
  static void save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
                   std::string_view application_data, const MapSettings& settings,
                   const MapFileOps& ops = MapFileOps{});
  /// Writes raw bytes atomically (used by save; exposed for tests). Throws MapStoreError.
  static void writeAtomically(const std::filesystem::path& path, std::string_view bytes,
                              const MapFileOps& ops = MapFileOps{});
  /// Throws MapStoreError (missing, unreadable, not a map, newer version, truncated, damaged).
  /// Files larger than `max_bytes` are refused from their size, unread.
  static LoadedMap load(const std::filesystem::path& path, const SimilarityMeasure& similarity,
                        std::uint64_t max_bytes = kDefaultMaxMapBytes);

  /// The newest good map at `path` (see "Recovery" above): `path` if it loads, else `path`.prev; every
  /// file that does not load is moved aside (when the directory allows). Nothing there: an empty result.
  /// Throws MapTooLargeError (and moves nothing) when a file is over the size cap.
  static RecoveredMap recover(const std::filesystem::path& path, const SimilarityMeasure& similarity,
                              std::uint64_t max_bytes = kDefaultMaxMapBytes);

  /// Empty when a map recorded with `recorded` settings can be continued by a run with `current` ones
  /// (keys present in both agree; a version-1 map recorded none), else a message naming both values.
  static std::string checkSettings(const MapSettings& recorded, const MapSettings& current,
                                   const std::string& name);

  /// Removes the temporary files of interrupted saves of `path` (".<name>.XXXXXX[.prev]" beside it).
  /// Returns how many were removed. Call it while holding the map's MapLock.
  static int removeOrphanedTemporaries(const std::filesystem::path& path);

  /// True when `path` is a readable map file whose framing verifies (magic, version, size, checksum);
  /// the payload is not parsed. writeAtomically keeps a replaced file as .prev only when this holds.
  static bool fileVerifies(const std::filesystem::path& path);

 private:
  /// The payload of a file image whose framing verifies. Throws MapStoreError saying what is wrong.
  static std::string_view verifiedPayload(std::string_view file, const std::string& name);
  /// Moves a file that did not load aside (see "Recovery"); returns what happened, for the log.
  static std::string moveAside(const std::filesystem::path& file);
};

}  // namespace toposlam
