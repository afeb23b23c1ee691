// MapStore: framing (magic, version, size, FNV-1a checksum) and atomic file replacement for map.tsm.
#include "toposlam/topology/map_store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "binary_io.hpp"

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

std::string MapStore::encode(const TopologyParticleFilter& filter, std::string_view application_data) {
  std::ostringstream state;
  filter.saveState(state);
  topology_detail::BinaryWriter payload;
  payload.bytes(state.str());
  payload.bytes(application_data);
  topology_detail::BinaryWriter file;
  for (char c : kMagic) file.u8(static_cast<std::uint8_t>(c));
  file.u32(kMapFormatVersion);
  file.u32(0);
  file.u64(payload.data().size());
  file.u64(fnv1a64(payload.data()));
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
  if (fnv1a64(payload) != checksum) throw MapStoreError(name + ": damaged map file (checksum mismatch)");
  return payload;
}

LoadedMap MapStore::decode(std::string_view file, const SimilarityMeasure& similarity,
                           const std::string& name) {
  const std::string_view payload = verifiedPayload(file, name);
  try {
    topology_detail::BinaryReader reader(payload);
    const std::string_view state = reader.bytes("filter state");
    LoadedMap loaded;
    loaded.application_data = std::string(reader.bytes("application data"));
    if (!reader.atEnd()) throw std::runtime_error("trailing bytes in the payload");
    std::istringstream state_stream{std::string(state)};
    loaded.filter = TopologyParticleFilter::loadState(state_stream, similarity);
    return loaded;
  } catch (const MapStoreError&) {
    throw;
  } catch (const std::exception& e) {
    throw MapStoreError(name + ": damaged map file (" + e.what() + ")");
  }
}

bool MapStore::fileVerifies(const std::filesystem::path& path) {
  std::error_code ignored;
  if (!std::filesystem::is_regular_file(path, ignored)) return false;
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) return false;
  try {
    verifiedPayload(content.str(), path.string());
    return true;
  } catch (const MapStoreError&) {
    return false;
  }
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

LoadedMap MapStore::load(const std::filesystem::path& path, const SimilarityMeasure& similarity) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapStoreError("cannot open map " + path.string() + ": " + errnoText(errno));
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw MapStoreError("cannot read map " + path.string());
  std::string hint;
  if (std::filesystem::exists(path.string() + ".prev"))
    hint = " (the previous map is kept in " + path.string() + ".prev)";
  try {
    return decode(content.str(), similarity, path.string());
  } catch (const MapStoreError& e) {
    throw MapStoreError(e.what() + hint);
  }
}

}  // namespace toposlam
