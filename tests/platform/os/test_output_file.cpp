// Tests of OutputFile: written under a temporary name and renamed on commit(); a write error (/dev/full,
// a file-size limit standing in for a full disk) is an OutputFileError naming the file, and the old
// content stays.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_files.hpp"
#include "toposlam/platform/output_file.hpp"

using namespace toposlam;
namespace fs = std::filesystem;
using toposlam::test::filesIn;
using toposlam::test::readAll;
using toposlam::test::TempFolder;

TEST_CASE("GIVEN an output file WHEN committed THEN the target holds the text and no temporary file is left",
          "[core][output][reliability]") {
  const TempFolder temp("commit");
  const fs::path& dir = temp.path;
  const fs::path target = dir / "frames.csv";
  std::ofstream(target) << "old";
  {
    OutputFile out(target);
    out << "frame,place\n0,1\n";
    CHECK(readAll(target) == "old");  // readers see the old file until the rename
    CHECK(filesIn(dir) == 2);
    out.commit();
    out.commit();  // idempotent
  }
  CHECK(readAll(target) == "frame,place\n0,1\n");
  CHECK(filesIn(dir) == 1);
  SECTION("not committed (an exception on the way): the target keeps its content, the temporary goes") {
    {
      OutputFile out(target);
      out << "half";
    }
    CHECK(readAll(target) == "frame,place\n0,1\n");
    CHECK(filesIn(dir) == 1);
  }
  fs::remove_all(dir);
}

TEST_CASE("GIVEN /dev/full WHEN written THEN commit throws naming it", "[core][output][reliability]") {
  if (!fs::exists("/dev/full")) {
    // The full-disk path needs /dev/full (a container may lack it): skipped (ctest's SKIP_RETURN_CODE).
    std::fprintf(stderr, "skipped: /dev/full does not exist here; the full-disk path cannot be exercised\n");
    std::_Exit(77);
  }
  OutputFile out("/dev/full");
  out << "image,expected\n";
  CHECK_THROWS_WITH(out.commit(), Catch::Contains("/dev/full: write failed: No space left on device"));
}

TEST_CASE("GIVEN a folder that does not exist WHEN an output file is opened there THEN the error names it",
          "[core][output][reliability]") {
  CHECK_THROWS_WITH(OutputFile("/nonexistent-toposlam-dir/x.csv"),
                    Catch::Contains("/nonexistent-toposlam-dir/x.csv: cannot create file"));
}

TEST_CASE("GIVEN a disk that fills up WHEN a large file is committed THEN it throws naming it and the old file stays",
          "[core][output][reliability]") {
  const TempFolder temp("full");
  const fs::path& dir = temp.path;
  const fs::path target = dir / "timing.csv";
  std::ofstream(target) << "old";
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    // RLIMIT_FSIZE stands in for a full disk: writes past 16 KB fail (EFBIG, SIGXFSZ ignored).
    signal(SIGXFSZ, SIG_IGN);
    rlimit limit{16 * 1024, 16 * 1024};
    setrlimit(RLIMIT_FSIZE, &limit);
    try {
      OutputFile out(target);
      for (int i = 0; i < 10000; ++i) out << i << ",0.1234,0.5678\n";
      out.commit();
      _exit(1);  // no error: wrong
    } catch (const OutputFileError& e) {
      const std::string what = e.what();
      _exit(what.find(target.string() + ": write failed: File too large") != std::string::npos ? 0 : 2);
    }
  }
  int status = 0;
  waitpid(child, &status, 0);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(readAll(target) == "old");
  CHECK(filesIn(dir) == 1);
  fs::remove_all(dir);
}

namespace {

/// The system's calls, counting fsyncs and failing the n-th (1-based; 0 = none) with `error`.
class CountingOps : public FileWriteOps {
 public:
  CountingOps(int fail_fsync, int error) : fail_fsync_(fail_fsync), error_(error) {}
  int fsync(int fd) const override {
    if (++fsyncs == fail_fsync_) {
      errno = error_;
      return -1;
    }
    return FileWriteOps::fsync(fd);
  }
  mutable int fsyncs = 0;

 private:
  int fail_fsync_;
  int error_;
};

}  // namespace

TEST_CASE("GIVEN an output file WHEN committed THEN the file and then its folder are fsynced, and a failed fsync is an error",
          "[core][output][reliability]") {
  const TempFolder temp("fsync");
  const fs::path target = temp.path / "places.csv";
  std::ofstream(target) << "old";
  SECTION("both fsyncs succeed: two calls (the file, then the folder, so the rename survives a power cut)") {
    const CountingOps ops(0, 0);
    OutputFile out(target, &ops);
    out << "place,node\n";
    out.commit();
    CHECK(ops.fsyncs == 2);
    CHECK(readAll(target) == "place,node\n");
    CHECK(filesIn(temp.path) == 1);
  }
  SECTION("the file's fsync fails (EIO): an error naming the file, the old content stays, no temporary file") {
    const CountingOps ops(1, EIO);
    OutputFile out(target, &ops);
    out << "place,node\n";
    CHECK_THROWS_WITH(out.commit(), Catch::Contains(target.string() + ": write failed: Input/output error"));
    CHECK(readAll(target) == "old");
    CHECK(filesIn(temp.path) == 1);
    // Committing again says the same, and touches nothing (the temporary file is gone already).
    CHECK_THROWS_WITH(out.commit(), Catch::Contains(target.string() + ": write failed: Input/output error"));
    CHECK(ops.fsyncs == 1);
    CHECK(readAll(target) == "old");
  }
  SECTION("the folder's fsync fails (EIO): the new file is in place and the error says it may not last") {
    const CountingOps ops(2, EIO);
    OutputFile out(target, &ops);
    out << "place,node\n";
    CHECK_THROWS_WITH(out.commit(), Catch::Contains("its folder could not be flushed"));
    CHECK(readAll(target) == "place,node\n");
    CHECK(filesIn(temp.path) == 1);
    CHECK_THROWS_WITH(out.commit(), Catch::Contains("its folder could not be flushed"));
    CHECK(ops.fsyncs == 2);
    CHECK(readAll(target) == "place,node\n");
  }
}
