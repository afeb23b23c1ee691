// MapStore's file functions and MapLock (map_files.hpp): the format and the file names come from
// topology (map_store.hpp), every system call from platform/os.
#include "toposlam/pipeline/map_files.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <memory>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

#include "toposlam/platform/file_system.hpp"

namespace toposlam {

namespace {

std::string errnoText(int error) { return std::strerror(error); }

/// The folder `path` is in ("." for a bare file name).
std::filesystem::path folderOf(const std::filesystem::path& path) {
  return path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
}

/// Throws MapStoreError naming `path` when `file` did not open as a regular file.
void requireOpen(const ReadableFile& file, const std::filesystem::path& path) {
  if (file.status() == ReadableFile::Status::cannot_open)
    throw MapStoreError("cannot open map " + path.string() + ": " + errnoText(file.error()));
  if (file.status() == ReadableFile::Status::not_regular)
    throw MapStoreError("cannot read map " + path.string() + ": not a regular file");
}

std::string sizeText(std::uint64_t bytes) {
  std::ostringstream out;
  if (bytes >= (1ull << 20)) {
    out.precision(1);
    out << std::fixed << static_cast<double>(bytes) / (1 << 20) << " MB";
  } else {
    out << bytes << " bytes";
  }
  return out.str();
}

/// "20240131T120501" in UTC.
std::string timestampNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%S", &utc);
  return text;
}

/// Moves a file that did not load aside (MapStore::damagedPath); returns what happened, for the log.
std::string moveAside(const std::filesystem::path& file) {
  const std::string timestamp = timestampNow();
  std::filesystem::path aside;
  // A hard link never replaces an existing name, so an earlier .damaged file is never overwritten.
  int error = 0;
  for (int attempt = 0; attempt < 100; ++attempt) {
    aside = MapStore::damagedPath(file, timestamp, attempt);
    error = linkFile(file, aside);
    if (error != EEXIST) break;
  }
  if (error != 0) return "could not move it aside (" + errnoText(error) + "); it is left where it is";
  if (const int unlink_error = removeFile(file); unlink_error != 0) {
    removeFile(aside);
    return "could not move it aside (" + errnoText(unlink_error) + "); it is left where it is";
  }
  // Keep the newest kMaxDamagedFiles of this file.
  std::vector<std::filesystem::path> damaged;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folderOf(file), ec))
    if (MapStore::isDamagedCopyOf(file, entry.path().filename().string())) damaged.push_back(entry.path());
  std::string pruned;
  for (const std::filesystem::path& copy : MapStore::damagedCopiesToRemove(std::move(damaged))) {
    std::filesystem::remove(copy, ec);
    pruned += (pruned.empty() ? "" : ", ") + copy.filename().string();
  }
  std::string text = "moved it to " + aside.string();
  if (!pruned.empty()) text += " (removed the oldest damaged copies: " + pruned + ")";
  return text;
}

}  // namespace

bool MapStore::fileVerifies(const std::filesystem::path& path) {
  // Streamed: a large map is checked in 1 MB pieces, never held in memory here.
  ReadableFile file(path);
  if (file.status() != ReadableFile::Status::open || file.size() < kMapHeaderSize) return false;
  std::string header(kMapHeaderSize, '\0');
  if (file.readFully(header.data(), header.size()) != 0) return false;
  MapFramingCheck check;
  if (!check.start(header, file.size())) return false;
  std::vector<char> chunk(1 << 20);
  for (std::uint64_t left = check.payloadSize(); left > 0;) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk.size()));
    if (file.readFully(chunk.data(), n) != 0) return false;
    check.add(chunk.data(), n);
    left -= n;
  }
  return check.verified();
}

void MapStore::writeAtomically(const std::filesystem::path& path, std::string_view bytes,
                               const MapFileOps& ops) {
  AtomicFileWrite write(path, kTemporaryInfix);
  if (const int error = write.create(); error != 0)
    throw MapStoreError("cannot create a temporary file in " + write.folder().string() + ": " +
                        errnoText(error));
  const std::string unchanged = " (the previous map file is unchanged)";
  if (const int error = write.write(bytes, ops); error != 0)
    throw MapStoreError("cannot write map " + path.string() + ": " + errnoText(error) + unchanged);
  if (const int error = write.sync(ops); error != 0)
    throw MapStoreError("cannot flush map " + path.string() + " to disk: " + errnoText(error) + unchanged);
  if (const int error = write.close(); error != 0)
    throw MapStoreError("cannot close map " + path.string() + ": " + errnoText(error) + unchanged);
  // The file being replaced becomes <path>.prev by a rename, then the new file takes <path>: at every
  // instant one of the two names holds a complete map, and they are never one file (a hard link made them
  // one until the second rename, so a kill in between left no older map). Between the renames <path> is
  // missing for a moment; recovery then loads <path>.prev. Only a file whose framing verifies is kept: a
  // damaged file must not push the last good map out of <path>.prev.
  const std::filesystem::path previous = previousPath(path);
  const bool keep_previous = fileVerifies(path);
  if (keep_previous && ops.rename(path.c_str(), previous.c_str()) != 0) {
    throw MapStoreError("cannot keep map " + path.string() + " as " + previous.string() + ": " +
                        errnoText(errno) + unchanged);
  }
  if (const int error = write.replaceTarget(ops); error != 0) {
    // Put the map back under its own name (the older .prev went with the first rename).
    if (keep_previous && ops.rename(previous.c_str(), path.c_str()) != 0) {
      throw MapStoreError("cannot replace map " + path.string() + ": " + errnoText(error) +
                          " (the previous map is kept as " + previous.string() + ")");
    }
    throw MapStoreError("cannot replace map " + path.string() + ": " + errnoText(error) + unchanged);
  }
  if (const int error = write.syncFolder(ops); error != 0) {
    throw MapStoreError("map " + path.string() +
                        " written but its directory could not be flushed: " + errnoText(error));
  }
}

void MapStore::checkWritable(const std::filesystem::path& path, const MapFileOps& ops) {
  const std::string folder = folderOf(path).string();
  const std::string cannot = "the map " + path.string() + " could not be saved: ";
  std::error_code ec;
  for (const std::filesystem::path& name : {path, previousPath(path)}) {
    const std::filesystem::file_status status = std::filesystem::symlink_status(name, ec);
    if (status.type() == std::filesystem::file_type::directory)
      throw MapStoreError(cannot + name.string() + " is a directory; remove it or choose another map path");
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status) &&
        !std::filesystem::is_symlink(status))
      throw MapStoreError(cannot + name.string() + " is not a regular file; remove it or choose another map path");
  }
  if (!std::filesystem::is_directory(folderOf(path), ec))
    throw MapStoreError(cannot + "its folder " + folder + " does not exist (or is not a folder)");
  // What a save does, on a probe file beside the map: create, write, fsync, rename; then remove it.
  AtomicFileWrite probe(path, kTemporaryInfix);
  if (const int error = probe.create(); error != 0)
    throw MapStoreError(cannot + "cannot create a file in " + folder + ": " + errnoText(error));
  const std::string probe_name = probePath(probe.temporaryPath());
  if (const int error = probe.write("toposlam map save probe\n", ops); error != 0)
    throw MapStoreError(cannot + "cannot write a file in " + folder + ": " + errnoText(error));
  if (const int error = probe.sync(ops); error != 0)
    throw MapStoreError(cannot + "cannot flush a file in " + folder + " to disk: " + errnoText(error));
  if (const int error = probe.close(); error != 0)
    throw MapStoreError(cannot + "cannot close a file in " + folder + ": " + errnoText(error));
  if (ops.rename(probe.temporaryPath().c_str(), probe_name.c_str()) != 0)
    throw MapStoreError(cannot + "cannot rename a file in " + folder + ": " + errnoText(errno));
  if (const int error = removeFile(probe_name); error != 0)
    throw MapStoreError(cannot + "cannot remove a file in " + folder + " (" + probe_name + "): " + errnoText(error));
}

void MapStore::save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
                    std::string_view application_data, const MapFileOps& ops) {
  writeAtomically(path, encode(filter, application_data), ops);
}

void MapStore::save(const std::filesystem::path& path, const TopologyParticleFilter& filter,
                    std::string_view application_data, const MapSettings& settings, const MapFileOps& ops) {
  writeAtomically(path, encode(filter, application_data, settings), ops);
}

LoadedMap MapStore::load(const std::filesystem::path& path, const SimilarityMeasure& similarity,
                         std::uint64_t max_bytes) {
  ReadableFile file(path);
  requireOpen(file, path);
  std::string hint;
  if (std::filesystem::exists(previousPath(path)))
    hint = " (the previous map is kept in " + previousPath(path).string() + ")";
  const std::uint64_t size = file.size();
  if (size > max_bytes) {
    throw MapTooLargeError("map " + path.string() + " is " + sizeText(size) + ", more than the cap of " +
                           sizeText(max_bytes) + " (map.max_mb); refused unread" + hint);
  }
  // Read once, into this one buffer, not zeroed first (hundreds of MB for a large map).
  const auto content = std::make_unique_for_overwrite<char[]>(static_cast<std::size_t>(size));
  if (const int error = file.readFully(content.get(), static_cast<std::size_t>(size)); error != 0)
    throw MapStoreError("cannot read map " + path.string() + ": " + errnoText(error));
  try {
    return decode(std::string_view(content.get(), static_cast<std::size_t>(size)), similarity, path.string());
  } catch (const MapStoreError& e) {
    throw MapStoreError(e.what() + hint);
  }
}

RecoveredMap MapStore::recover(const std::filesystem::path& path, const SimilarityMeasure& similarity,
                               std::uint64_t max_bytes) {
  RecoveredMap result;
  for (const std::filesystem::path& candidate : recoveryCandidates(path)) {
    std::error_code ec;
    if (!std::filesystem::exists(candidate, ec)) continue;
    try {
      result.map = load(candidate, similarity, max_bytes);
      result.loaded_from = candidate;
      return result;
    } catch (const MapTooLargeError&) {
      throw;  // not damage: nothing is moved, the caller refuses to start (a bigger cap, or another map)
    } catch (const MapStoreError& e) {
      result.problems.push_back(std::string(e.what()) + "; " + moveAside(candidate));
    }
  }
  return result;
}

int MapStore::removeOrphanedTemporaries(const std::filesystem::path& path) {
  int removed = 0;
  std::error_code ec;
  std::vector<std::filesystem::path> orphans;
  for (const auto& entry : std::filesystem::directory_iterator(folderOf(path), ec))
    if (isTemporaryOf(path, entry.path().filename().string())) orphans.push_back(entry.path());
  for (const auto& orphan : orphans)
    if (std::filesystem::remove(orphan, ec)) ++removed;
  return removed;
}

// ------------------------------------------------------------------------------------------------------------

MapLock MapLock::acquire(const std::filesystem::path& map_path) {
  FileLockFailure failure;
  std::optional<FileLock> lock = FileLock::tryAcquire(map_path.string() + ".lock", failure);
  if (lock) return MapLock(std::move(*lock));
  const std::string locked = failure.path.string();
  if (failure.cannot_open)
    throw MapStoreError("cannot create the lock file " + locked + ": " + errnoText(failure.error));
  if (failure.error == EWOULDBLOCK) {
    const std::string holder = failure.holder > 0 ? " (process " + std::to_string(failure.holder) + ")" : "";
    throw MapStoreError("the map " + map_path.string() + " is in use by another toposlam process" + holder +
                        ": it holds " + locked + "; stop it or use another map path");
  }
  throw MapStoreError("cannot lock " + locked + ": " + errnoText(failure.error));
}

}  // namespace toposlam
