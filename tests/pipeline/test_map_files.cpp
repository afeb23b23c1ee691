// Tests of the map on disk (MapStore's file functions, MapLock; moved here from tests/topology with them):
// atomic save, refusal of damaged / truncated / newer files, a full disk, recovery, the lock, orphans.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <signal.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <random>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "test_files.hpp"
#include "topology/fake_similarity.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/pipeline/map_files.hpp"
#include "toposlam/topology/map_store.hpp"

using namespace toposlam;
using toposlam::test::placeSimilarity;
using toposlam::test::smallFilter;
using toposlam::test::taggedFingerprint;

namespace fs = std::filesystem;
using toposlam::test::filesIn;
using toposlam::test::readAll;
using toposlam::test::TempFolder;

namespace {

void writeAll(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

/// Fails every write after `budget` bytes with ENOSPC, like a full disk.
class FullDisk : public MapFileOps {
 public:
  explicit FullDisk(std::size_t budget) : budget_(budget) {}
  long write(int fd, const void* data, std::size_t size) const override {
    if (written_ >= budget_) {
      errno = ENOSPC;
      return -1;
    }
    const std::size_t n = std::min(size, budget_ - written_);
    const long done = MapFileOps::write(fd, data, n);
    if (done > 0) written_ += static_cast<std::size_t>(done);
    return done;
  }

 private:
  std::size_t budget_;
  mutable std::size_t written_ = 0;
};

}  // namespace

TEST_CASE("GIVEN a saved map WHEN loaded THEN the filter and application data come back exactly",
          "[topology][map]") {
  auto sim = placeSimilarity();
  const TempFolder temp("roundtrip");
  const fs::path& dir = temp.path;
  auto filter = smallFilter(sim, 10);
  MapStore::save(dir / "map.tsm", *filter, "places");
  LoadedMap loaded = MapStore::load(dir / "map.tsm", sim);
  CHECK(loaded.application_data == "places");
  CHECK(MapStore::encode(*loaded.filter, "places") == MapStore::encode(*filter, "places"));
  CHECK(loaded.filter->observationCount() == 10);
  CHECK(filesIn(dir) == 1);  // no temporary file left behind

  WHEN("it is saved again") {
    filter->step(taggedFingerprint(2));
    MapStore::save(dir / "map.tsm", *filter, "places2");
    THEN("the replaced file is kept as map.tsm.prev") {
      CHECK(MapStore::load(dir / "map.tsm.prev", sim).application_data == "places");
      CHECK(MapStore::load(dir / "map.tsm", sim).application_data == "places2");
    }
  }
}

TEST_CASE("GIVEN damaged map files WHEN loaded THEN each is refused with a clear error", "[topology][map]") {
  auto sim = placeSimilarity();
  const TempFolder temp("damaged");
  const fs::path& dir = temp.path;
  auto filter = smallFilter(sim, 8);
  const fs::path good = dir / "map.tsm";
  MapStore::save(good, *filter);
  const std::string bytes = readAll(good);
  REQUIRE(bytes.size() > 64);

  // framing_verifies: MapStore::fileVerifies checks magic, version, size and checksum, not the payload.
  auto refused = [&](const std::string& content, const std::string& expected, bool framing_verifies = false) {
    const fs::path bad = dir / "bad.tsm";
    writeAll(bad, content);
    try {
      MapStore::load(bad, sim);
      FAIL("loaded a bad map");
    } catch (const MapStoreError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(expected) != std::string::npos);
    }
    // Refusing a file leaves it as it was on disk and creates nothing beside it.
    CHECK(readAll(bad) == content);
    CHECK(filesIn(dir) == 2);
    CHECK(MapStore::fileVerifies(bad) == framing_verifies);
  };
  SECTION("a flipped payload byte") {
    std::string damaged = bytes;
    damaged[bytes.size() / 2] = static_cast<char>(damaged[bytes.size() / 2] ^ 0x10);
    refused(damaged, "checksum mismatch");
  }
  SECTION("a truncated file") { refused(bytes.substr(0, bytes.size() - 7), "truncated"); }
  SECTION("a truncated header") { refused(bytes.substr(0, 12), "truncated"); }
  SECTION("a newer version") {
    std::string newer = bytes;
    newer[8] = static_cast<char>(kMapFormatVersion + 1);  // format version, little-endian u32 after the magic
    refused(newer, "newer toposlam");
  }
  SECTION("not a map at all") {
    refused("hello world, this is not a map file at all......", "not a toposlam map");
  }
  SECTION("an empty file") { refused("", "not a toposlam map"); }
  SECTION("a missing file") {
    CHECK_THROWS_WITH(MapStore::load(dir / "missing.tsm", sim), Catch::Contains("cannot open map"));
  }
  SECTION("a consistent checksum over a nonsense payload") {
    // Re-frame garbage with a correct checksum: the payload parser must refuse it without crashing.
    std::string payload(40, '\x7f');
    std::string framed = bytes.substr(0, 16);
    for (int i = 0; i < 8; ++i) framed.push_back(static_cast<char>((payload.size() >> (8 * i)) & 0xff));
    const std::uint64_t sum = mapPayloadChecksum(kMapFormatVersion, payload);
    for (int i = 0; i < 8; ++i) framed.push_back(static_cast<char>((sum >> (8 * i)) & 0xff));
    refused(framed + payload, "damaged map file", true);
  }
}

TEST_CASE("GIVEN a damaged map on disk WHEN a new map is saved over it THEN .prev keeps the last good map",
          "[topology][map]") {
  auto sim = placeSimilarity();
  const TempFolder temp("rotate");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 5);
  MapStore::save(path, *filter, "first");
  MapStore::save(path, *filter, "second");  // map.tsm.prev = "first"
  REQUIRE(MapStore::load(dir / "map.tsm.prev", sim).application_data == "first");
  CHECK(MapStore::fileVerifies(path));

  std::string damaged = readAll(path);
  damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x10);
  writeAll(path, damaged);
  REQUIRE_FALSE(MapStore::fileVerifies(path));

  MapStore::save(path, *filter, "third");
  THEN("the damaged file is dropped and .prev still holds the last map that verified") {
    CHECK(MapStore::load(path, sim).application_data == "third");
    CHECK(MapStore::load(dir / "map.tsm.prev", sim).application_data == "first");
    CHECK(filesIn(dir) == 2);
  }
  WHEN("a good map is saved over a good map") {
    MapStore::save(path, *filter, "fourth");
    THEN("the replaced good map becomes .prev") {
      CHECK(MapStore::load(dir / "map.tsm.prev", sim).application_data == "third");
    }
  }
}

TEST_CASE("GIVEN a full disk WHEN a map is saved THEN a clear error is thrown and the old file is intact",
          "[topology][map]") {
  auto sim = placeSimilarity();
  const TempFolder temp("fulldisk");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 6);
  MapStore::save(path, *filter, "old");
  const std::string old_bytes = readAll(path);
  filter->step(taggedFingerprint(1));
  for (std::size_t budget : {std::size_t{0}, std::size_t{10}, std::size_t{200}}) {
    FullDisk disk(budget);
    CHECK_THROWS_WITH(
        MapStore::save(path, *filter, "new", disk),
        Catch::Contains("No space left on device") && Catch::Contains("previous map file is unchanged"));
    CHECK(readAll(path) == old_bytes);
    CHECK(filesIn(dir) == 1);  // the temporary file was removed
  }
  CHECK(MapStore::load(path, sim).application_data == "old");
}

TEST_CASE("GIVEN a directory that does not exist WHEN a map is saved there THEN the error names it",
          "[topology][map]") {
  auto sim = placeSimilarity();
  auto filter = smallFilter(sim, 2);
  CHECK_THROWS_WITH(MapStore::save("/nonexistent-toposlam-dir/map.tsm", *filter),
                    Catch::Contains("cannot create a temporary file in /nonexistent-toposlam-dir"));
}

// ---- recovery, lock, orphans, size cap, settings (issue 19) ------------------------------------------------

namespace {

std::vector<std::string> namesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::size_t countPrefix(const fs::path& dir, const std::string& prefix) {
  std::size_t n = 0;
  for (const std::string& name : namesIn(dir)) n += name.rfind(prefix, 0) == 0 ? 1 : 0;
  return n;
}

void flipMiddleByte(const fs::path& path) {
  std::string bytes = readAll(path);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  writeAll(path, bytes);
}

}  // namespace

TEST_CASE("GIVEN a damaged map and a good .prev WHEN recovered THEN .prev is loaded and the damaged file kept aside",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("recover");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 5);
  MapStore::save(path, *filter, "first");
  MapStore::save(path, *filter, "second");  // .prev = first
  flipMiddleByte(path);
  const std::string damaged_bytes = readAll(path);

  RecoveredMap recovered = MapStore::recover(path, sim);
  REQUIRE(recovered.map);
  CHECK(recovered.map->application_data == "first");
  CHECK(recovered.loaded_from == fs::path(path.string() + ".prev"));
  REQUIRE(recovered.problems.size() == 1);
  CHECK_THAT(recovered.problems[0], Catch::Contains("checksum mismatch") && Catch::Contains("moved it to " + path.string() + ".damaged-"));
  CHECK_FALSE(fs::exists(path));
  REQUIRE(countPrefix(dir, "map.tsm.damaged-") == 1);

  WHEN("the robot saves twice after resuming from .prev") {
    MapStore::save(path, *recovered.map->filter, "resumed-1");
    CHECK(MapStore::load(dir / "map.tsm.prev", sim).application_data == "first");  // the last good map survives
    MapStore::save(path, *recovered.map->filter, "resumed-2");
    CHECK(MapStore::load(dir / "map.tsm.prev", sim).application_data == "resumed-1");
  }
  WHEN("a second damaged map is recovered in the same second") {
    MapStore::save(path, *filter, "third");
    flipMiddleByte(path);
    RecoveredMap again = MapStore::recover(path, sim);
    THEN("the earlier damaged file is untouched and the new one has a name of its own") {
      CHECK(countPrefix(dir, "map.tsm.damaged-") == 2);
      bool found_first = false;
      for (const std::string& name : namesIn(dir))
        if (name.rfind("map.tsm.damaged-", 0) == 0 && readAll(dir / name) == damaged_bytes) found_first = true;
      CHECK(found_first);
      REQUIRE(again.map);
      CHECK(again.map->application_data == "first");
    }
  }
  WHEN("many damaged maps are recovered") {
    for (int i = 0; i < kMaxDamagedFiles + 3; ++i) {
      MapStore::save(path, *filter, "again" + std::to_string(i));
      flipMiddleByte(path);
      (void)MapStore::recover(path, sim);
    }
    THEN("only the newest kMaxDamagedFiles are kept") {
      CHECK(countPrefix(dir, "map.tsm.damaged-") == static_cast<std::size_t>(kMaxDamagedFiles));
    }
  }
}

TEST_CASE("GIVEN a damaged map and a damaged .prev WHEN recovered THEN nothing loads and both are kept aside",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("recover-both");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 4);
  MapStore::save(path, *filter, "first");
  MapStore::save(path, *filter, "second");
  flipMiddleByte(path);
  flipMiddleByte(dir / "map.tsm.prev");
  RecoveredMap recovered = MapStore::recover(path, sim);
  CHECK_FALSE(recovered.map);
  CHECK(recovered.problems.size() == 2);
  CHECK(countPrefix(dir, "map.tsm.damaged-") == 1);
  CHECK(countPrefix(dir, "map.tsm.prev.damaged-") == 1);
  CHECK(MapStore::recover(dir / "nothing.tsm", sim).problems.empty());
}

TEST_CASE("GIVEN a damaged map in a read-only directory WHEN recovered THEN the log says it could not be moved",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  // Under the system temp folder, not the build tree: the child runs as nobody, who may not be able to
  // reach a checkout inside a private folder (a mktemp -d clone, as CI's may be).
  const fs::path dir = fs::temp_directory_path() / ("toposlam-recover-readonly-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec | fs::perms::others_read |
                           fs::perms::others_exec);
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 4);
  MapStore::save(path, *filter, "first");
  MapStore::save(path, *filter, "second");
  flipMiddleByte(path);
  fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                           fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  // root ignores directory permissions: the check runs in a child as nobody.
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    if (::geteuid() == 0 && ::setresuid(65534, 65534, 65534) != 0) _exit(3);
    RecoveredMap r = MapStore::recover(path, sim);
    const bool ok = r.map && r.map->application_data == "first" && r.problems.size() == 1 &&
                    r.problems[0].find("could not move it aside") != std::string::npos &&
                    r.problems[0].find("moved it to") == std::string::npos && fs::exists(path);
    _exit(ok ? 0 : 1);
  }
  int status = 0;
  waitpid(child, &status, 0);
  fs::permissions(dir, fs::perms::owner_all, fs::perm_options::add);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(countPrefix(dir, "map.tsm.damaged-") == 0);
  fs::remove_all(dir);
}

TEST_CASE("GIVEN a map locked by one writer WHEN a second one locks it THEN it is refused naming the lock file",
          "[topology][map][reliability]") {
  const TempFolder temp("lock");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  {
    MapLock first = MapLock::acquire(path);
    CHECK(first.lockedPath() == fs::path(path.string() + ".lock"));
    CHECK_THROWS_WITH(MapLock::acquire(path),
                      Catch::Contains("in use by another toposlam process (process " + std::to_string(::getpid())) &&
                          Catch::Contains(path.string() + ".lock"));
    MapLock moved = std::move(first);
    CHECK_THROWS_AS(MapLock::acquire(path), MapStoreError);
  }
  CHECK_NOTHROW(MapLock::acquire(path));  // released with its owner
  CHECK_NOTHROW(MapLock::acquire(dir / "other.tsm"));
}

TEST_CASE("GIVEN temporary files of saves a kill -9 interrupted WHEN removed at start THEN only those go",
          "[topology][map][reliability]") {
  const TempFolder temp("orphans");
  const fs::path& dir = temp.path;
  for (const char* name : {".map.tsm.Ab3dE9", ".map.tsm.Zz0000.prev", "map.tsm", "map.tsm.prev", ".map.tsm.lock",
                           ".map.tsm.toolong7", ".other.tsm.Ab3dE9", "notes.txt"})
    writeAll(dir / name, "x");
  CHECK(MapStore::removeOrphanedTemporaries(dir / "map.tsm") == 2);
  CHECK(namesIn(dir) == std::vector<std::string>{".map.tsm.lock", ".map.tsm.toolong7", ".other.tsm.Ab3dE9",
                                                 "map.tsm", "map.tsm.prev", "notes.txt"});
}

TEST_CASE("GIVEN a map file over the size cap WHEN loaded or recovered THEN it is refused unread and moved nowhere",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("sizecap");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 4);
  MapStore::save(path, *filter, "small");
  const auto size = fs::file_size(path);
  CHECK_NOTHROW(MapStore::load(path, sim, size));
  CHECK_THROWS_AS(MapStore::load(path, sim, size - 1), MapTooLargeError);
  CHECK_THROWS_WITH(MapStore::load(path, sim, size - 1), Catch::Contains("more than the cap") &&
                                                          Catch::Contains("refused unread"));
  // A 2 GB (sparse) file is refused from its size at once under the default cap.
  const fs::path huge = dir / "huge.tsm";
  { std::ofstream(huge) << "TSLMAP"; }
  fs::resize_file(huge, 2ull << 30);
  CHECK_THROWS_AS(MapStore::load(huge, sim), MapTooLargeError);
  CHECK_THROWS_AS(MapStore::recover(huge, sim), MapTooLargeError);
  CHECK(fs::exists(huge));
  CHECK(countPrefix(dir, "huge.tsm.damaged") == 0);
  fs::remove(huge);
}

namespace {

/// A map image of format 5 re-framed as format 4 wrote it: the same payload without the views section.
std::string asVersion4(const std::string& image) {
  REQUIRE(image[8] == 5);
  std::size_t at = 32;
  for (int field = 0; field < 3; ++field) {  // bytes(filter state), bytes(application data), bytes(settings)
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i) size |= std::uint64_t{static_cast<unsigned char>(image[at + i])} << (8 * i);
    at += 8 + size;
  }
  const std::string payload = image.substr(32, at - 32);
  std::string out = image.substr(0, 8) + std::string("\x04\0\0\0\0\0\0\0", 8);
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((payload.size() >> (8 * i)) & 0xff));
  const std::uint64_t sum = mapPayloadChecksum(4, payload);
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((sum >> (8 * i)) & 0xff));
  return out + payload;
}

}  // namespace

TEST_CASE("GIVEN a map made with ORB keypoints WHEN checked against a SIFT run THEN refused naming both",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("settings");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  auto filter = smallFilter(sim, 3);
  VpackConfig orb;
  VpackConfig sift;
  sift.keypoints.backend = KeypointBackend::Sift;
  MapStore::save(path, *filter, "data", fingerprintMapSettings(orb));
  const LoadedMap loaded = MapStore::load(path, sim);
  CHECK(loaded.settings == MapSettings{{"keypoints", "orb"}});
  CHECK(MapStore::checkSettings(loaded.settings, fingerprintMapSettings(orb), "m").empty());
  CHECK_THAT(MapStore::checkSettings(loaded.settings, fingerprintMapSettings(sift), path.string()),
             Catch::Contains(path.string()) && Catch::Contains("keypoints=orb") && Catch::Contains("keypoints=sift"));

  SECTION("a version-2 map (FNV-1a checksum) still loads; versions 3 and 4 carry zlib's CRC-32") {
    std::string v3 = asVersion4(MapStore::encode(*filter, "data", fingerprintMapSettings(orb)));
    REQUIRE(v3[8] == 4);
    CHECK(MapStore::decode(v3, sim).settings == MapSettings{{"keypoints", "orb"}});
    v3[8] = 3;  // the same layout: version 4 only records more settings
    CHECK(MapStore::decode(v3, sim).settings == MapSettings{{"keypoints", "orb"}});
    const std::string payload = v3.substr(32);
    std::string v2 = v3.substr(0, 8);
    v2 += std::string("\x02\0\0\0\0\0\0\0", 8);
    for (int i = 0; i < 8; ++i) v2.push_back(static_cast<char>((payload.size() >> (8 * i)) & 0xff));
    const std::uint64_t sum = fnv1a64(payload);
    for (int i = 0; i < 8; ++i) v2.push_back(static_cast<char>((sum >> (8 * i)) & 0xff));
    v2 += payload;
    const LoadedMap old = MapStore::decode(v2, sim);
    CHECK(old.application_data == "data");
    CHECK(old.settings == fingerprintMapSettings(orb));
    // The same bytes with a version-3 header but the FNV sum are refused: each version its own checksum.
    std::string mixed = v2;
    mixed[8] = 3;
    CHECK_THROWS_WITH(MapStore::decode(mixed, sim), Catch::Contains("checksum mismatch"));
    // CRC-32's standard check value.
    CHECK(mapPayloadChecksum(3, "123456789") == 0xCBF43926u);
    CHECK(mapPayloadChecksum(2, "123456789") == fnv1a64("123456789"));
  }
  SECTION("a version-1 map (no settings) still loads and is accepted") {
    // Re-frame the payload without the settings block, as version 1 wrote it.
    const std::string v3 = asVersion4(MapStore::encode(*filter, "data"));
    std::string payload = v3.substr(32);
    REQUIRE(payload.substr(payload.size() - 8) == std::string(8, '\0'));  // bytes("") of the empty settings
    payload.resize(payload.size() - 8);
    std::string v1 = v3.substr(0, 8);
    v1 += std::string("\x01\0\0\0\0\0\0\0", 8);
    for (int i = 0; i < 8; ++i) v1.push_back(static_cast<char>((payload.size() >> (8 * i)) & 0xff));
    const std::uint64_t sum = fnv1a64(payload);
    for (int i = 0; i < 8; ++i) v1.push_back(static_cast<char>((sum >> (8 * i)) & 0xff));
    v1 += payload;
    const LoadedMap old = MapStore::decode(v1, sim);
    CHECK(old.application_data == "data");
    CHECK(old.settings.empty());
    CHECK(MapStore::checkSettings(old.settings, fingerprintMapSettings(sift), "m").empty());
  }
}

TEST_CASE("GIVEN saves killed with SIGKILL at random moments WHEN the map is recovered THEN it always loads and "
          "the orphaned temporaries are removed",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("kill9");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  // Three map images of different sizes; whichever survives must be one of them, whole.
  std::vector<std::string> images;
  for (int steps : {4, 8, 12}) images.push_back(MapStore::encode(*smallFilter(sim, steps), "steps" + std::to_string(steps)));
  MapStore::writeAtomically(path, images[0]);
  std::mt19937 random(19);  // seeded: the same kill moments every run
  std::uniform_int_distribution<int> delay_us(0, 3000);
  int orphans_removed = 0;
  constexpr int kRuns = 60;
  for (int run = 0; run < kRuns; ++run) {
    const pid_t child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      for (std::size_t k = 0;; ++k) MapStore::writeAtomically(path, images[k % images.size()]);
    }
    const int wait_us = delay_us(random);
    timespec pause{0, static_cast<long>(wait_us) * 1000};  // the moment of the kill, not a synchronisation
    nanosleep(&pause, nullptr);
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    orphans_removed += MapStore::removeOrphanedTemporaries(path);
    RecoveredMap recovered = MapStore::recover(path, sim);
    INFO("run " << run << ", killed after " << wait_us << " us");
    REQUIRE(recovered.map);
    CHECK(recovered.problems.empty());
    const std::string& data = recovered.map->application_data;
    CHECK((data == "steps4" || data == "steps8" || data == "steps12"));
    for (const std::string& name : namesIn(dir)) CHECK((name == "map.tsm" || name == "map.tsm.prev"));
  }
  // Some kills land inside a save (a temporary file left behind); how many depends on the machine's speed.
  WARN("orphaned temporary files removed after " << kRuns << " kills: " << orphans_removed);
}

namespace {

/// Kills the process (SIGKILL, as kill -9 would) when a save makes its `kill_at`-th rename (1-based), before
/// that rename happens: nothing after it runs, no destructor, no clean-up.
class KillAtRename : public MapFileOps {
 public:
  explicit KillAtRename(int kill_at) : kill_at_(kill_at) {}
  int rename(const char* from, const char* to) const override {
    if (++renames_ == kill_at_) ::raise(SIGKILL);
    return MapFileOps::rename(from, to);
  }

 private:
  int kill_at_;
  mutable int renames_ = 0;
};

/// The inode of `path`, or 0 when it does not exist.
std::uintmax_t inodeOf(const fs::path& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<std::uintmax_t>(st.st_ino) : 0;
}

}  // namespace

TEST_CASE("GIVEN a map and its .prev WHEN a save is killed before, between or after its two renames THEN map.tsm or "
          ".prev is a complete map, they are never one file, and recovery loads the newest that was complete",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("kill-renames");
  const fs::path& dir = temp.path;
  const fs::path path = dir / "map.tsm";
  const fs::path previous = dir / "map.tsm.prev";
  const std::string older = MapStore::encode(*smallFilter(sim, 4), "older");
  const std::string current = MapStore::encode(*smallFilter(sim, 8), "current");
  const std::string next = MapStore::encode(*smallFilter(sim, 12), "next");
  // kill_at 1: before the first rename (map -> .prev); 2: between the renames; 3: no kill (2 renames).
  const int kill_at = GENERATE(1, 2, 3);
  INFO("killed at rename " << kill_at);
  MapStore::writeAtomically(path, older);
  MapStore::writeAtomically(path, current);  // map.tsm = current, .prev = older
  REQUIRE(readAll(previous) == older);
  REQUIRE(inodeOf(path) != inodeOf(previous));

  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    MapStore::writeAtomically(path, next, KillAtRename(kill_at));
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  CHECK(WIFSIGNALED(status) == (kill_at <= 2));

  // At every instant one of the two names holds a complete map, and they are two files.
  CHECK((MapStore::fileVerifies(path) || MapStore::fileVerifies(previous)));
  if (fs::exists(path) && fs::exists(previous)) CHECK(inodeOf(path) != inodeOf(previous));
  const std::string expected_map = kill_at == 1 ? current : kill_at == 2 ? "" : next;
  const std::string expected_previous = kill_at == 1 ? older : current;
  CHECK((fs::exists(path) ? readAll(path) : std::string()) == expected_map);
  CHECK(readAll(previous) == expected_previous);

  // The next start: the killed save's temporary goes, the newest complete map loads.
  CHECK(MapStore::removeOrphanedTemporaries(path) == (kill_at <= 2 ? 1 : 0));
  RecoveredMap recovered = MapStore::recover(path, sim);
  REQUIRE(recovered.map);
  CHECK(recovered.problems.empty());
  CHECK(recovered.map->application_data == (kill_at == 1 ? "current" : kill_at == 2 ? "current" : "next"));
  CHECK(recovered.loaded_from == (kill_at == 2 ? previous : path));
  // And the next save after it restores both names, as two files.
  MapStore::writeAtomically(path, next);
  CHECK(MapStore::fileVerifies(path));
  CHECK(inodeOf(path) != inodeOf(previous));
  CHECK(namesIn(dir) == std::vector<std::string>{"map.tsm", "map.tsm.prev"});
}

namespace {

/// Fails a save's `fail_at`-th rename (1-based) with EIO.
class FailRename : public MapFileOps {
 public:
  explicit FailRename(int fail_at) : fail_at_(fail_at) {}
  int rename(const char* from, const char* to) const override {
    if (++renames_ == fail_at_) {
      errno = EIO;
      return -1;
    }
    return MapFileOps::rename(from, to);
  }

 private:
  int fail_at_;
  mutable int renames_ = 0;
};

}  // namespace

TEST_CASE("GIVEN a map WHEN the rename that puts the new map in place fails THEN the map is back under its name",
          "[topology][map][reliability]") {
  auto sim = placeSimilarity();
  const TempFolder temp("fail-rename");
  const fs::path path = temp.path / "map.tsm";
  const std::string current = MapStore::encode(*smallFilter(sim, 8), "current");
  MapStore::writeAtomically(path, current);
  const int fail_at = GENERATE(1, 2);
  try {
    MapStore::writeAtomically(path, MapStore::encode(*smallFilter(sim, 12), "next"), FailRename(fail_at));
    FAIL("the save did not fail");
  } catch (const MapStoreError& e) {
    INFO(e.what());
    CHECK_THAT(e.what(), Catch::Contains(path.string()) && Catch::Contains(std::strerror(EIO)) &&
                             Catch::Contains("the previous map file is unchanged"));
  }
  CHECK(readAll(path) == current);
  CHECK(namesIn(temp.path) == std::vector<std::string>{"map.tsm"});
}

TEST_CASE("GIVEN map paths that cannot be saved WHEN checked at start THEN the problem is named, and a good path "
          "leaves nothing behind",
          "[topology][map][reliability]") {
  const TempFolder temp("writable");
  const fs::path& dir = temp.path;
  auto refusal = [](const fs::path& path) -> std::string {
    try {
      MapStore::checkWritable(path);
    } catch (const MapStoreError& e) {
      return e.what();
    }
    return {};
  };
  SECTION("a good folder: the probe file is made and removed") {
    CHECK(refusal(dir / "map.tsm").empty());
    CHECK(filesIn(dir) == 0);
  }
  SECTION("a directory at the map path") {
    fs::create_directory(dir / "map.tsm");
    CHECK_THAT(refusal(dir / "map.tsm"), Catch::Contains((dir / "map.tsm").string() + " is a directory"));
  }
  SECTION("a directory at the .prev path") {
    fs::create_directory(dir / "map.tsm.prev");
    CHECK_THAT(refusal(dir / "map.tsm"), Catch::Contains((dir / "map.tsm.prev").string() + " is a directory"));
  }
  SECTION("a folder that does not exist") {
    CHECK_THAT(refusal(dir / "missing" / "map.tsm"), Catch::Contains("folder " + (dir / "missing").string() +
                                                                     " does not exist"));
  }
  SECTION("a folder where no file can be created") {
    // Root ignores permission bits; sysfs takes no new file, even from root.
    fs::path folder = "/sys";
    if (geteuid() != 0) {
      folder = dir / "read-only";
      fs::create_directory(folder);
      fs::permissions(folder, fs::perms::owner_read | fs::perms::owner_exec);
    }
    CHECK_THAT(refusal(folder / "map.tsm"), Catch::Contains("cannot create a file in " + folder.string()));
    std::error_code ignored;  // so that the folder can be removed (root: there is none)
    fs::permissions(dir / "read-only", fs::perms::owner_all, fs::perm_options::replace, ignored);
  }
  SECTION("a full disk") {
    try {
      MapStore::checkWritable(dir / "map.tsm", FullDisk(0));
      FAIL("not refused");
    } catch (const MapStoreError& e) {
      CHECK_THAT(e.what(), Catch::Contains("cannot write a file in") && Catch::Contains(std::strerror(ENOSPC)));
    }
    CHECK(filesIn(dir) == 0);
  }
}
