// MapStore: the map file (map.tsm) that lets a robot stop and go on where it left off.
//
// Layout (little-endian):
//   magic "TSLMAP\r\n" (8 bytes; the CR LF catches text-mode mangling)
//   u32 format version (kMapFormatVersion)   u32 reserved (0)
//   u64 payload size                          u64 FNV-1a 64 checksum of the payload
//   payload: bytes(filter state, TopologyParticleFilter::saveState) bytes(application data)
// where bytes(x) = u64 size + x. The application data is opaque to MapStore (the `map` command keeps
// its place/frame bookkeeping there).
//
// Writing is atomic: a temporary file in the same directory is written, fsync'ed, renamed over the
// target, and the directory is fsync'ed. The file it replaces is kept as "<path>.prev" (a hard link),
// but only when that file verifies (framing and checksum), so saving over a damaged map never pushes
// the last good one out of .prev.
// Any failure (e.g. a full disk) throws MapStoreError and leaves the old file untouched.
// Loading refuses a wrong magic, a newer version, a truncated or damaged file with a MapStoreError that
// says which; the file on disk is never modified by loading.
//
// Thread-safety: the functions are reentrant; do not save to the same path from two threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

inline constexpr std::uint32_t kMapFormatVersion = 1;

class MapStoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
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

struct LoadedMap {
  std::unique_ptr<TopologyParticleFilter> filter;
  std::string application_data;
};

class MapStore {
 public:
  /// The whole file image of `filter` (+ application data). Throws std::logic_error during a step.
  static std::string encode(const TopologyParticleFilter& filter, std::string_view application_data = {});
  /// Parses a file image; `name` is used in error messages. Throws MapStoreError.
  static LoadedMap decode(std::string_view file, const SimilarityMeasure& similarity,
                          const std::string& name = "map");

  /// Atomically replaces `path` (see above). Throws MapStoreError.
  static void save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
                   std::string_view application_data = {}, const MapFileOps& ops = MapFileOps{});
  /// Writes raw bytes atomically (used by save; exposed for tests). Throws MapStoreError.
  static void writeAtomically(const std::filesystem::path& path, std::string_view bytes,
                              const MapFileOps& ops = MapFileOps{});
  /// Throws MapStoreError (missing, unreadable, not a map, newer version, truncated, damaged).
  static LoadedMap load(const std::filesystem::path& path, const SimilarityMeasure& similarity);

  /// True when `path` is a readable map file whose framing verifies (magic, version, size, checksum);
  /// the payload is not parsed. writeAtomically keeps a replaced file as .prev only when this holds.
  static bool fileVerifies(const std::filesystem::path& path);

 private:
  /// The payload of a file image whose framing verifies. Throws MapStoreError saying what is wrong.
  static std::string_view verifiedPayload(std::string_view file, const std::string& name);
};

}  // namespace toposlam
