// The map file on disk: MapStore's file functions (save, load, recover, ...) and MapLock. What a map file
// holds and the policies for the files beside it (.prev, damaged copies, temporaries) are topology's,
// with no I/O (toposlam/topology/map_store.hpp); this is where they meet the file system, through
// platform/os (toposlam/platform/atomic_file.hpp, file_lock.hpp, file_system.hpp), which an algorithm
// may not include. Used by the topology stage (periodic and final saves), `toposlam map` and toposlamd.
//
// save()/writeAtomically() replace a map atomically and keep the file replaced as <path>.prev when it
// verifies; any failure (e.g. a full disk) throws MapStoreError and leaves the old file untouched.
// checkWritable() proves at start that a save can succeed (the programs call it before any frame).
// load() never modifies the file on disk; a file larger than the size cap is refused from its size
// before anything is read, and a file is read once, into one buffer. recover() is the daemon's start:
// the newest file that loads, damaged ones moved aside. MapLock keeps a second writer off a map.
//
// Thread-safety: the functions are reentrant; do not save to the same path from two threads.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "toposlam/platform/atomic_file.hpp"
#include "toposlam/platform/file_lock.hpp"
#include "toposlam/topology/map_store.hpp"

namespace toposlam {

/// The system calls a map save writes through (platform/os); tests inject failures (a full disk) by
/// overriding them.
using MapFileOps = FileWriteOps;

/// What MapStore::recover found.
struct RecoveredMap {
  std::optional<LoadedMap> map;       ///< empty: no file loaded (start a new map)
  std::filesystem::path loaded_from;  ///< the file `map` came from (the map or its .prev)
  std::vector<std::string> problems;  ///< one line per file that did not load and what became of it
};

/// An exclusive advisory lock (flock) on a map, held while the object lives. Movable.
class MapLock {
 public:
  /// Locks `map_path` through "<map_path>.lock" (created if needed; when the directory is read-only,
  /// the directory itself is locked). Throws MapStoreError naming the file when another process holds
  /// it (with that process' id when known).
  static MapLock acquire(const std::filesystem::path& map_path);
  /// The file (or directory) locked.
  const std::filesystem::path& lockedPath() const { return lock_.lockedPath(); }

 private:
  explicit MapLock(FileLock lock) : lock_(std::move(lock)) {}
  FileLock lock_;
};

namespace MapStore {

/// Atomically replaces `path` (see above). Throws MapStoreError.
void save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
          std::string_view application_data = {}, const MapFileOps& ops = MapFileOps{});
void save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
          std::string_view application_data, const MapSettings& settings,
          const MapFileOps& ops = MapFileOps{});
/// Writes raw bytes atomically (used by save and by the topology stage's snapshots). Throws MapStoreError.
void writeAtomically(const std::filesystem::path& path, std::string_view bytes,
                     const MapFileOps& ops = MapFileOps{});
/// Throws MapStoreError (missing, unreadable, not a map, newer version, truncated, damaged).
/// Files larger than `max_bytes` are refused from their size, unread (MapTooLargeError).
LoadedMap load(const std::filesystem::path& path, const SimilarityMeasure& similarity,
               std::uint64_t max_bytes = kDefaultMaxMapBytes);

/// The newest good map at `path`: `path` if it loads, else `path`.prev; every file that does not load is
/// moved aside (when the directory allows). Nothing there: an empty result.
/// Throws MapTooLargeError (and moves nothing) when a file is over the size cap.
RecoveredMap recover(const std::filesystem::path& path, const SimilarityMeasure& similarity,
                     std::uint64_t max_bytes = kDefaultMaxMapBytes);

/// Throws MapStoreError naming the problem unless a map can be saved at `path`: neither it nor its .prev is
/// a directory (or another non-file), its folder exists, and a probe file beside it can be created, written,
/// fsync'ed, renamed and removed (the steps of a save). Leaves nothing behind (a probe a kill interrupted
/// is a temporary that removeOrphanedTemporaries recognises). Permissions, a read-only file system, a
/// full disk or a missing folder show here; a file-size limit (ulimit -f) does not (the first save over
/// it fails with EFBIG).
void checkWritable(const std::filesystem::path& path, const MapFileOps& ops = MapFileOps{});

/// Removes the temporary files of interrupted saves of `path` (".<name>.XXXXXX[.prev|.probe]" beside it).
/// Returns how many were removed. Call it while holding the map's MapLock.
int removeOrphanedTemporaries(const std::filesystem::path& path);

/// True when `path` is a readable map file whose framing verifies (magic, version, size, checksum);
/// the payload is not parsed. writeAtomically keeps a replaced file as .prev only when this holds.
bool fileVerifies(const std::filesystem::path& path);

}  // namespace MapStore

}  // namespace toposlam
