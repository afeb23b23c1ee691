// The file-system calls of platform/os: an atomic replacement leaves the old file and no temporary when a
// step fails (an injected full disk), a second flock on one file is refused naming its holder, a regular
// file is read whole and a short one says EIO, a hard link never replaces a name.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "test_files.hpp"
#include "toposlam/platform/atomic_file.hpp"
#include "toposlam/platform/file_lock.hpp"
#include "toposlam/platform/file_system.hpp"

using namespace toposlam;
namespace fs = std::filesystem;
using toposlam::test::filesIn;
using toposlam::test::readAll;
using toposlam::test::TempFolder;

namespace {

/// Every write fails with ENOSPC.
class FullDisk : public FileWriteOps {
 public:
  long write(int, const void*, std::size_t) const override {
    errno = ENOSPC;
    return -1;
  }
};

}  // namespace

SCENARIO(
    "GIVEN a file WHEN it is replaced atomically THEN the new content is there, or on a failure the old "
    "one and no temporary") {
  const TempFolder temp("atomic");
  const fs::path& dir = temp.path;
  const fs::path target = dir / "out.txt";
  {
    AtomicFileWrite write(target, ".");
    REQUIRE(write.create() == 0);
    CHECK(fs::path(write.temporaryPath()).filename().string().rfind(".out.txt.", 0) == 0);
    CHECK(write.folder() == dir);
    CHECK(write.write("first", FileWriteOps{}) == 0);
    CHECK(write.sync(FileWriteOps{}) == 0);
    CHECK(write.close() == 0);
    CHECK(write.replaceTarget(FileWriteOps{}) == 0);
    CHECK(write.syncFolder(FileWriteOps{}) == 0);
  }
  CHECK(readAll(target) == "first");
  CHECK((fs::status(target).permissions() & fs::perms::others_read) == fs::perms::others_read);
  {
    AtomicFileWrite write(target, ".tmp-");
    REQUIRE(write.create() == 0);
    CHECK(write.write("second", FullDisk{}) == ENOSPC);
  }  // not replaced: the temporary goes with the object
  CHECK(readAll(target) == "first");
  CHECK(filesIn(dir) == 1);
  AtomicFileWrite nowhere(dir / "missing" / "out.txt", ".");
  CHECK(nowhere.create() == ENOENT);
  fs::remove_all(dir);
}

SCENARIO(
    "GIVEN a file locked once WHEN it is locked again THEN that is refused naming this process, until "
    "the lock's owner is gone") {
  const TempFolder temp("lock");
  const fs::path& dir = temp.path;
  const fs::path file = dir / "x.lock";
  {
    FileLockFailure failure;
    std::optional<FileLock> first = FileLock::tryAcquire(file, failure);
    REQUIRE(first);
    CHECK(first->lockedPath() == file);
    FileLockFailure refused;
    CHECK_FALSE(FileLock::tryAcquire(file, refused));
    CHECK_FALSE(refused.cannot_open);
    CHECK(refused.error == EWOULDBLOCK);
    CHECK(refused.holder == static_cast<long>(::getpid()));
    CHECK(refused.path == file);
    FileLock moved = std::move(*first);
    first.reset();
    CHECK_FALSE(FileLock::tryAcquire(file, refused));  // the moved lock still holds it
  }
  FileLockFailure failure;
  CHECK(FileLock::tryAcquire(file, failure));
  CHECK_FALSE(FileLock::tryAcquire(dir / "missing" / "x.lock", failure));
  CHECK(failure.cannot_open);
  CHECK(failure.error == ENOENT);
  fs::remove_all(dir);
}

SCENARIO("GIVEN a lock held WHEN it is released THEN its lock file is gone, unless the name leads elsewhere by then") {
  const TempFolder temp("lock-release");
  const fs::path& dir = temp.path;
  const fs::path file = dir / "map.tsm.lock";
  FileLockFailure failure;
  {
    std::optional<FileLock> lock = FileLock::tryAcquire(file, failure);
    REQUIRE(lock);
    CHECK(fs::exists(file));
    FileLock moved = std::move(*lock);
    lock.reset();
    CHECK(fs::exists(file));  // the moved lock still holds it
  }
  CHECK_FALSE(fs::exists(file));  // no stale lock after a clean release
  {
    std::optional<FileLock> lock = FileLock::tryAcquire(file, failure);
    REQUIRE(lock);
    fs::remove(file);
    { std::ofstream(file) << "someone else's"; }  // another file under the name: not ours to remove
  }
  CHECK(readAll(file) == "someone else's");
  {
    std::optional<FileLock> lock = FileLock::tryAcquire(file, failure);  // a lock file left by others
    REQUIRE(lock);
  }
  CHECK_FALSE(fs::exists(file));
  fs::remove_all(dir);
}

SCENARIO("GIVEN a lock file that is a symbolic link or a hard link to another file WHEN locked THEN the other "
         "file is never written") {
  const TempFolder temp("lock-links");
  const fs::path& dir = temp.path;
  { std::ofstream(dir / "victim") << "keep me"; }
  fs::create_symlink(dir / "victim", dir / "map.tsm.lock");
  FileLockFailure failure;
  CHECK_FALSE(FileLock::tryAcquire(dir / "map.tsm.lock", failure));
  CHECK(failure.cannot_open);
  CHECK(failure.error == ELOOP);
  CHECK(readAll(dir / "victim") == "keep me");
  fs::remove(dir / "map.tsm.lock");
  fs::create_hard_link(dir / "victim", dir / "map.tsm.lock");
  {
    std::optional<FileLock> lock = FileLock::tryAcquire(dir / "map.tsm.lock", failure);
    CHECK(lock);  // locked, but not truncated nor written
  }
  CHECK(readAll(dir / "victim") == "keep me");
  CHECK(fs::exists(dir / "map.tsm.lock"));  // a second name of another file: never removed
  fs::remove_all(dir);
}

SCENARIO(
    "GIVEN files and folders WHEN read, linked, renamed and removed THEN each says what the system said") {
  const TempFolder temp("calls");
  const fs::path& dir = temp.path;
  { std::ofstream(dir / "a") << "hello"; }
  ReadableFile a(dir / "a");
  REQUIRE(a.status() == ReadableFile::Status::open);
  CHECK(a.size() == 5);
  std::string text(5, '\0');
  CHECK(a.readFully(text.data(), text.size()) == 0);
  CHECK(text == "hello");
  char more = 0;
  CHECK(a.readFully(&more, 1) == EIO);  // the file ended first
  CHECK(ReadableFile(dir).status() == ReadableFile::Status::not_regular);
  const ReadableFile missing(dir / "missing");
  CHECK(missing.status() == ReadableFile::Status::cannot_open);
  CHECK(missing.error() == ENOENT);

  CHECK(linkFile(dir / "a", dir / "b") == 0);
  CHECK(readAll(dir / "b") == "hello");
  CHECK(linkFile(dir / "a", dir / "b") == EEXIST);  // never replaces a name
  { std::ofstream(dir / "c") << "other"; }
  CHECK(renameFile(dir / "c", dir / "b") == 0);  // replaces
  CHECK(readAll(dir / "b") == "other");
  CHECK(removeFile(dir / "b") == 0);
  CHECK(removeFile(dir / "b") == ENOENT);
  fs::remove_all(dir);
}
