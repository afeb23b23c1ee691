// `toposlam segment` end to end through the real binary: the run folder it writes on the sample frames,
// and clear errors (non-zero exit, "toposlam: error: ..." naming the problem) for bad input.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

const std::string kToposlam = std::string(TOPOSLAM_BINARY_DIR) + "/src/apps/toposlam/toposlam";

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

Result runToposlam(const std::string& arguments) {
  const fs::path log =
      fs::temp_directory_path() / ("toposlam-segment-cli-" + std::to_string(::getpid()) + ".log");
  const std::string command = kToposlam + " " + arguments + " > " + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  Result result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  result.output = text.str();
  fs::remove(log);
  return result;
}

std::size_t lineCount(const fs::path& path) {
  std::ifstream in(path);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  return lines;
}

fs::path freshFolder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

}  // namespace

TEST_CASE("GIVEN the sample frames WHEN `toposlam segment` runs THEN it writes the run folder",
          "[segmentation][cli]") {
  if (!fs::exists(kToposlam)) FAIL("build the toposlam target first: " << kToposlam);
  const fs::path out = freshFolder("toposlam-segment-cli");
  const Result r = runToposlam("segment images:" + std::string(TOPOSLAM_SAMPLES_DIR) + "/samples --out " +
                               out.string() + " --window 5 --quiet");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  // The default preset's similarity (docs/matching.md); --window 5 alone is a window of 5 frames.
  CHECK(r.output.find("84 frames -> 9 places kept, 0 dropped") != std::string::npos);
  CHECK(lineCount(out / "frames.csv") == 85);
  CHECK(lineCount(out / "timing.csv") == 85);
  CHECK(lineCount(out / "places.csv") == 10);
  CHECK(lineCount(out / "dropped_places.csv") == 1);
  std::ifstream svg(out / "lambda2.svg");
  std::string first;
  std::getline(svg, first);
  CHECK(first.rfind("<?xml", 0) == 0);
  std::ifstream places(out / "places.csv");
  std::string header;
  std::getline(places, header);
  CHECK(header == "place,first,last,representative,keypoints,node,end");
  fs::remove_all(out);
}

TEST_CASE("GIVEN bad input WHEN `toposlam segment` runs THEN it fails with an actionable message",
          "[segmentation][cli]") {
  if (!fs::exists(kToposlam)) FAIL("build the toposlam target first: " << kToposlam);
  const fs::path out = freshFolder("toposlam-segment-cli-bad");
  SECTION("a source that does not exist") {
    const Result r = runToposlam("segment images:/no/such/folder --out " + out.string() + " --quiet");
    INFO(r.output);
    CHECK(r.exit_code != 0);
    CHECK(r.output.find("toposlam: error:") != std::string::npos);
    CHECK(r.output.find("/no/such/folder") != std::string::npos);
  }
  SECTION("delta larger than gamma") {
    const Result r = runToposlam("segment images:" + std::string(TOPOSLAM_SAMPLES_DIR) + "/samples --out " +
                                 out.string() + " --gamma 0.3 --delta 0.4 --quiet");
    INFO(r.output);
    CHECK(r.exit_code != 0);
    CHECK(r.output.find("delta") != std::string::npos);
  }
  SECTION("an unknown cut placement") {
    const Result r = runToposlam("segment images:" + std::string(TOPOSLAM_SAMPLES_DIR) + "/samples --out " +
                                 out.string() + " --cut middle --quiet");
    INFO(r.output);
    CHECK(r.exit_code == 2);  // a usage error
    CHECK(r.output.find("window-split") != std::string::npos);
  }
  SECTION("an unknown representative rule") {
    const Result r = runToposlam("segment images:" + std::string(TOPOSLAM_SAMPLES_DIR) + "/samples --out " +
                                 out.string() + " --representative middle --quiet");
    INFO(r.output);
    CHECK(r.exit_code == 2);  // a usage error
    CHECK(r.output.find("--representative") != std::string::npos);
    CHECK(r.output.find("place-medoid") != std::string::npos);
  }
  SECTION("an output folder that cannot be created") {
    const Result r = runToposlam("segment images:" + std::string(TOPOSLAM_SAMPLES_DIR) +
                                 "/samples --out /proc/toposlam-cannot-write --quiet");
    INFO(r.output);
    CHECK(r.exit_code != 0);
    CHECK(r.output.find("/proc/toposlam-cannot-write") != std::string::npos);
  }
  fs::remove_all(out);
}
