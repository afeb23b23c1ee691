// MapStore: framing (magic, version, size, FNV-1a checksum), atomic file replacement, recovery from a
// damaged file, and the lock of map.tsm.
#include "toposlam/topology/map_store.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <istream>
#include <sstream>
#include <streambuf>
#include <vector>
#include <zlib.h>

#include "binary_io.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"

namespace toposlam {

namespace {

constexpr char kMagic[8] = {'T', 'S', 'L', 'M', 'A', 'P', '\r', '\n'};
constexpr std::size_t kHeaderSize = 8 + 4 + 4 + 8 + 8;

std::string errnoText(int error) { return std::strerror(error); }

/// Closes the descriptor and removes the temporary file unless released.
struct TempFile {
  std::string path;
  int fd = -1;
  bool keep = false;
  ~TempFile() {
    if (fd >= 0) ::close(fd);
    if (!keep && !path.empty()) ::unlink(path.c_str());
  }
};

/// Closes a descriptor on scope exit.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

/// An istream over bytes it does not own (no copy of a large filter state).
class ViewBuffer : public std::streambuf {
 public:
  explicit ViewBuffer(std::string_view data) {
    char* begin = const_cast<char*>(data.data());  // only read: the get area is never written through
    setg(begin, begin, begin + data.size());
  }
};

/// Reads exactly `size` bytes at the current offset; false on a short read or an error (errno set).
bool readFully(int fd, char* out, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(fd, out + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;  // the file shrank under us
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

/// Opens a regular file for reading and returns its size; throws MapStoreError naming it.
int openRegular(const std::filesystem::path& path, std::uint64_t& size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw MapStoreError("cannot open map " + path.string() + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw MapStoreError("cannot read map " + path.string() + ": not a regular file");
  }
  size = static_cast<std::uint64_t>(st.st_size);
  return fd;
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

/// "20240131T120501" in UTC.
std::string timestampNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%S", &utc);
  return text;
}

}  // namespace

long MapFileOps::write(int fd, const void* data, std::size_t size) const { return ::write(fd, data, size); }
int MapFileOps::fsync(int fd) const { return ::fsync(fd); }

std::uint64_t fnv1a64(std::string_view data) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (char c : data) {
    hash ^= static_cast<std::uint8_t>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

namespace {

/// The checksum of one map format version, fed piece by piece (a large map is verified streamed).
class PayloadChecksum {
 public:
  explicit PayloadChecksum(std::uint32_t version) : crc_(version >= 3) {}
  void add(const char* data, std::size_t size) {
    if (crc_) {
      // zlib takes at most a uInt per call.
      while (size > 0) {
        const auto n = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
        crc32_ = ::crc32(crc32_, reinterpret_cast<const Bytef*>(data), n);
        data += n;
        size -= n;
      }
      return;
    }
    for (std::size_t i = 0; i < size; ++i) {
      fnv_ ^= static_cast<std::uint8_t>(data[i]);
      fnv_ *= 0x100000001b3ULL;
    }
  }
  std::uint64_t value() const { return crc_ ? static_cast<std::uint64_t>(crc32_) : fnv_; }

 private:
  bool crc_;
  uLong crc32_ = ::crc32(0L, Z_NULL, 0);
  std::uint64_t fnv_ = 0xcbf29ce484222325ULL;
};

}  // namespace

std::uint64_t mapPayloadChecksum(std::uint32_t version, std::string_view payload) {
  PayloadChecksum checksum(version);
  checksum.add(payload.data(), payload.size());
  return checksum.value();
}

bool settingDiffers(const MapSettings& recorded, const MapSettings& current, const std::string& key) {
  const auto a = recorded.find(key);
  const auto b = current.find(key);
  return a != recorded.end() && b != current.end() && a->second != b->second;
}

MapSettings fingerprintMapSettings(const VpackConfig& config) {
  return MapSettings{{"keypoints", toString(config.keypoints.backend)}};
}

std::string MapStore::encode(const TopologyParticleFilter& filter, std::string_view application_data,
                             const MapSettings& settings) {
  return encode(filter.freeze(), application_data, settings);
}

std::string MapStore::encode(const FrozenTopologyState& frozen, std::string_view application_data,
                             const MapSettings& settings) {
  std::ostringstream state;
  frozen.saveState(state);
  topology_detail::BinaryWriter payload;
  payload.bytes(state.str());
  payload.bytes(application_data);
  payload.bytes(settingsText(settings));
  topology_detail::BinaryWriter file;
  for (char c : kMagic) file.u8(static_cast<std::uint8_t>(c));
  file.u32(kMapFormatVersion);
  file.u32(0);
  file.u64(payload.data().size());
  file.u64(mapPayloadChecksum(kMapFormatVersion, payload.data()));
  std::string out = file.take();
  out += payload.data();
  return out;
}

std::string_view MapStore::verifiedPayload(std::string_view file, const std::string& name) {
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

LoadedMap MapStore::decode(std::string_view file, const SimilarityMeasure& similarity,
                           const std::string& name) {
  const std::string_view payload = verifiedPayload(file, name);
  const std::uint32_t version = topology_detail::BinaryReader(file.substr(8, 4)).u32("version");
  try {
    topology_detail::BinaryReader reader(payload);
    const std::string_view state = reader.bytes("filter state");
    LoadedMap loaded;
    loaded.application_data = std::string(reader.bytes("application data"));
    if (version >= 2) loaded.settings = parseSettings(reader.bytes("settings"), name);
    if (!reader.atEnd()) throw std::runtime_error("trailing bytes in the payload");
    ViewBuffer buffer(state);
    std::istream state_stream(&buffer);
    loaded.filter = TopologyParticleFilter::loadState(state_stream, similarity);
    return loaded;
  } catch (const MapStoreError&) {
    throw;
  } catch (const std::exception& e) {
    throw MapStoreError(name + ": damaged map file (" + e.what() + ")");
  }
}

bool MapStore::fileVerifies(const std::filesystem::path& path) {
  // Streamed: a large map is checked in 1 MB pieces, never held in memory here.
  std::uint64_t file_size = 0;
  Fd fd;
  try {
    fd.fd = openRegular(path, file_size);
  } catch (const MapStoreError&) {
    return false;
  }
  if (file_size < kHeaderSize) return false;
  std::string header(kHeaderSize, '\0');
  if (!readFully(fd.fd, header.data(), header.size())) return false;
  if (std::memcmp(header.data(), kMagic, 8) != 0) return false;
  topology_detail::BinaryReader fields(std::string_view(header).substr(8));
  const std::uint32_t version = fields.u32("version");
  fields.u32("reserved");
  const std::uint64_t size = fields.u64("size");
  const std::uint64_t checksum = fields.u64("checksum");
  if (version == 0 || version > kMapFormatVersion || file_size - kHeaderSize != size) return false;
  PayloadChecksum hash(version);
  std::vector<char> chunk(1 << 20);
  for (std::uint64_t left = size; left > 0;) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk.size()));
    if (!readFully(fd.fd, chunk.data(), n)) return false;
    hash.add(chunk.data(), n);
    left -= n;
  }
  return hash.value() == checksum;
}

void MapStore::writeAtomically(const std::filesystem::path& path, std::string_view bytes,
                               const MapFileOps& ops) {
  const std::filesystem::path directory =
      path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  TempFile temp;
  {
    std::string name = ".";
    name += path.filename().string();
    name += ".XXXXXX";
    const std::string pattern = (directory / name).string();
    std::vector<char> buffer(pattern.begin(), pattern.end());
    buffer.push_back('\0');
    temp.fd = ::mkstemp(buffer.data());
    if (temp.fd < 0) {
      throw MapStoreError("cannot create a temporary file in " + directory.string() + ": " +
                          errnoText(errno));
    }
    temp.path = buffer.data();
    ::fchmod(temp.fd, 0644);  // mkstemp creates 0600; a map is not secret (best effort)
  }
  std::size_t written = 0;
  while (written < bytes.size()) {
    const long n = ops.write(temp.fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : ENOSPC;
      throw MapStoreError("cannot write map " + path.string() + ": " + errnoText(error) +
                          " (the previous map file is unchanged)");
    }
    written += static_cast<std::size_t>(n);
  }
  if (ops.fsync(temp.fd) != 0) {
    throw MapStoreError("cannot flush map " + path.string() + " to disk: " + errnoText(errno) +
                        " (the previous map file is unchanged)");
  }
  const int fd = temp.fd;
  temp.fd = -1;
  if (::close(fd) != 0) {
    throw MapStoreError("cannot close map " + path.string() + ": " + errnoText(errno) +
                        " (the previous map file is unchanged)");
  }
  // Keep the file being replaced as <path>.prev (best effort: a hard link, no copy), but only when its
  // framing verifies: a damaged file must not push the last good map out of <path>.prev.
  if (fileVerifies(path)) {
    const std::string previous = path.string() + ".prev";
    const std::string previous_temp = temp.path + ".prev";
    if (::link(path.c_str(), previous_temp.c_str()) == 0) {
      if (::rename(previous_temp.c_str(), previous.c_str()) != 0) ::unlink(previous_temp.c_str());
    }
  }
  if (::rename(temp.path.c_str(), path.c_str()) != 0) {
    throw MapStoreError("cannot replace map " + path.string() + ": " + errnoText(errno) +
                        " (the previous map file is unchanged)");
  }
  temp.keep = true;
  const int dir_fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    const int result = ops.fsync(dir_fd);
    const int error = errno;
    ::close(dir_fd);
    if (result != 0 && error != EINVAL) {
      throw MapStoreError("map " + path.string() +
                          " written but its directory could not be flushed: " + errnoText(error));
    }
  }
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
  std::uint64_t size = 0;
  Fd fd;
  fd.fd = openRegular(path, size);
  std::string hint;
  if (std::filesystem::exists(path.string() + ".prev"))
    hint = " (the previous map is kept in " + path.string() + ".prev)";
  if (size > max_bytes) {
    throw MapTooLargeError("map " + path.string() + " is " + sizeText(size) + ", more than the cap of " +
                           sizeText(max_bytes) + " (map.max_mb); refused unread" + hint);
  }
  std::string content(static_cast<std::size_t>(size), '\0');  // read once, into this one buffer
  if (!readFully(fd.fd, content.data(), content.size()))
    throw MapStoreError("cannot read map " + path.string() + ": " + std::strerror(errno));
  try {
    return decode(content, similarity, path.string());
  } catch (const MapStoreError& e) {
    throw MapStoreError(e.what() + hint);
  }
}

std::string MapStore::moveAside(const std::filesystem::path& file) {
  const std::string stem = file.string() + ".damaged-" + timestampNow();
  std::string aside = stem;
  // link() never replaces an existing name, so an earlier .damaged file is never overwritten.
  int result = -1;
  int error = 0;
  for (int n = 1; n <= 100; ++n) {
    result = ::link(file.c_str(), aside.c_str());
    error = errno;
    if (result == 0 || error != EEXIST) break;
    aside = stem + "-" + std::to_string(n);
  }
  if (result != 0) {
    return "could not move it aside (" + std::string(std::strerror(error)) + "); it is left where it is";
  }
  if (::unlink(file.c_str()) != 0) {
    const int unlink_error = errno;
    ::unlink(aside.c_str());
    return "could not move it aside (" + std::string(std::strerror(unlink_error)) + "); it is left where it is";
  }
  // Keep the newest kMaxDamagedFiles of this file (names sort by their timestamps).
  std::vector<std::filesystem::path> damaged;
  std::error_code ec;
  const std::filesystem::path directory =
      file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  const std::string prefix = file.filename().string() + ".damaged-";
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) == 0) damaged.push_back(entry.path());
  }
  std::sort(damaged.begin(), damaged.end());  // oldest first: "<ts>" < "<ts>-1" < "<later ts>"
  std::string pruned;
  while (damaged.size() > static_cast<std::size_t>(kMaxDamagedFiles)) {
    std::filesystem::remove(damaged.front(), ec);
    pruned += (pruned.empty() ? "" : ", ") + damaged.front().filename().string();
    damaged.erase(damaged.begin());
  }
  std::string text = "moved it to " + aside;
  if (!pruned.empty()) text += " (removed the oldest damaged copies: " + pruned + ")";
  return text;
}

RecoveredMap MapStore::recover(const std::filesystem::path& path, const SimilarityMeasure& similarity,
                               std::uint64_t max_bytes) {
  RecoveredMap result;
  const std::filesystem::path candidates[] = {path, std::filesystem::path(path.string() + ".prev")};
  for (const std::filesystem::path& candidate : candidates) {
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

int MapStore::removeOrphanedTemporaries(const std::filesystem::path& path) {
  const std::filesystem::path directory =
      path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  const std::string prefix = "." + path.filename().string() + ".";
  int removed = 0;
  std::error_code ec;
  std::vector<std::filesystem::path> orphans;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    std::string rest = entry.path().filename().string();
    if (rest.rfind(prefix, 0) != 0) continue;
    rest = rest.substr(prefix.size());
    if (rest.size() == 6 + 5 && rest.compare(6, 5, ".prev") == 0) rest.resize(6);
    // mkstemp's six characters: letters and digits.
    if (rest.size() == 6 && std::all_of(rest.begin(), rest.end(), [](char c) {
          return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
        }))
      orphans.push_back(entry.path());
  }
  for (const auto& orphan : orphans)
    if (std::filesystem::remove(orphan, ec)) ++removed;
  return removed;
}

// ------------------------------------------------------------------------------------------------------------

MapLock MapLock::acquire(const std::filesystem::path& map_path) {
  std::filesystem::path locked = map_path.string() + ".lock";
  int fd = ::open(locked.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0 && (errno == EROFS || errno == EACCES || errno == EPERM)) {
    // A read-only state directory: lock the directory itself (saves will fail there anyway, but a second
    // daemon is still refused).
    locked = map_path.has_parent_path() ? map_path.parent_path() : std::filesystem::path(".");
    fd = ::open(locked.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  }
  if (fd < 0) throw MapStoreError("cannot create the lock file " + locked.string() + ": " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    std::string holder;
    char text[32] = {};
    if (::pread(fd, text, sizeof text - 1, 0) > 0) {
      const long pid = std::strtol(text, nullptr, 10);
      if (pid > 0) holder = " (process " + std::to_string(pid) + ")";
    }
    ::close(fd);
    if (error == EWOULDBLOCK) {
      throw MapStoreError("the map " + map_path.string() + " is in use by another toposlam process" + holder +
                          ": it holds " + locked.string() + "; stop it or use another map path");
    }
    throw MapStoreError("cannot lock " + locked.string() + ": " + std::strerror(error));
  }
  // Record our process id for the message a second process prints (best effort).
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0 && ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
      // ignored: the lock itself is what matters
    }
  }
  return MapLock(fd, locked);
}

MapLock::MapLock(MapLock&& other) noexcept : fd_(other.fd_), locked_(std::move(other.locked_)) { other.fd_ = -1; }

MapLock& MapLock::operator=(MapLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    locked_ = std::move(other.locked_);
    other.fd_ = -1;
  }
  return *this;
}

MapLock::~MapLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the flock
}

}  // namespace toposlam
