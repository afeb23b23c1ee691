// Tests of frame-source URI parsing and its typed getters' error messages.
#include <catch2/catch.hpp>

#include <filesystem>

#include "toposlam/io/source_uri.hpp"
#include "toposlam/pipeline/frame_source.hpp"

using namespace toposlam;

TEST_CASE("GIVEN source URIs WHEN parsed THEN scheme, path and query are split as documented", "[io]") {
  const SourceUri sim = parseSourceUri("sim:office?route=loop2&fps=5&size=320x240&seed=1");
  CHECK(sim.scheme == "sim");
  CHECK(sim.path == "office");
  CHECK(sim.query.size() == 4);
  CHECK(sim.getString("route", "") == "loop2");
  CHECK(sim.getDouble("fps", 0, 0, 100) == 5.0);
  CHECK(sim.getSize("size", {1, 1}) == std::pair<int, int>{320, 240});
  CHECK(sim.getInt("seed", 0, 0, 10) == 1);
  CHECK(sim.getInt("missing", 7, 0, 10) == 7);

  const SourceUri plain = parseSourceUri("/data/run1");
  CHECK(plain.scheme.empty());
  CHECK(plain.path == "/data/run1");

  // A glob's '?' wildcard stays in the path; only a trailing key=value list is a query.
  const SourceUri glob = parseSourceUri("images:/data/img?.jpg");
  CHECK(glob.path == "/data/img?.jpg");
  CHECK(glob.query.empty());
  const SourceUri glob_with_rate = parseSourceUri("images:/data/img?.jpg?rate=2");
  CHECK(glob_with_rate.path == "/data/img?.jpg");
  CHECK(glob_with_rate.getDouble("rate", 0, 0, 10) == 2.0);

  CHECK(parseSourceUri("IMAGES:x").scheme == "images");
  CHECK(parseSourceUri("./a:b").scheme.empty());
}

TEST_CASE("GIVEN bad query values WHEN read THEN the error names the key, the value and the allowed range", "[io]") {
  const SourceUri uri = parseSourceUri("sim:office?fps=fast&size=320by240&seed=-3&moved=maybe&light=dusk&bogus=1");
  CHECK_THROWS_AS(uri.getDouble("fps", 5, 0.1, 1000), FrameSourceError);
  CHECK_THROWS_WITH(uri.getDouble("fps", 5, 0.1, 1000), Catch::Contains("fps=fast") && Catch::Contains("0.1..1000"));
  CHECK_THROWS_WITH(uri.getSize("size", {320, 240}), Catch::Contains("size=320by240") && Catch::Contains("WxH"));
  CHECK_THROWS_WITH(uri.getInt("seed", 1, 0, 100), Catch::Contains("seed=-3") && Catch::Contains("0..100"));
  CHECK_THROWS_WITH(uri.getBool("moved", false), Catch::Contains("moved=maybe"));
  CHECK_THROWS_WITH(uri.getChoice("light", "day", {"day", "night"}), Catch::Contains("light=dusk") && Catch::Contains("night"));
  CHECK_THROWS_WITH(uri.requireOnly({"fps", "size", "seed", "moved", "light"}),
                    Catch::Contains("bogus") && Catch::Contains("allowed: fps, size"));
  CHECK_THROWS_WITH(parseSourceUri(""), Catch::Contains("empty"));
  CHECK_THROWS_WITH(parseSourceUri("sim:office?fps=1&fps=2"), Catch::Contains("fps") && Catch::Contains("twice"));
}

TEST_CASE("GIVEN file-source URIs WHEN made absolute THEN relative paths resolve against the working directory and queries stay", "[io]") {
  const std::string cwd = std::filesystem::current_path().lexically_normal().string();
  CHECK(absoluteSourceUri("images:frames/../run1?rate=5") == "images:" + cwd + "/run1?rate=5");
  CHECK(absoluteSourceUri("video:clip.mp4") == "video:" + cwd + "/clip.mp4");
  CHECK(absoluteSourceUri("run2") == cwd + "/run2");
  CHECK(absoluteSourceUri("images:/data/img?.jpg?rate=2") == "images:/data/img?.jpg?rate=2");
  CHECK(absoluteSourceUri("sim:office?route=loop2") == "sim:office?route=loop2");
  CHECK(absoluteSourceUri("v4l2:/dev/video0?fps=30") == "v4l2:/dev/video0?fps=30");
}

TEST_CASE("GIVEN source URIs WHEN a map records them THEN scheme and location count and the query does not", "[io]") {
  const std::string cwd = std::filesystem::current_path().lexically_normal().string();
  CHECK(sourceIdentity("sim:office?route=loop2") == "sim:office");
  CHECK(sourceIdentity("sim:office?route=loop&fps=3") == sourceIdentity("sim:office?route=loop2"));
  CHECK(sourceIdentity("v4l2:/dev/video0?size=640x480&fps=30&format=yuyv") == "v4l2:/dev/video0");
  CHECK(sourceIdentity("v4l2:/dev/video0") != sourceIdentity("v4l2:/dev/video1"));
  CHECK(sourceIdentity("libcamera:1") == "libcamera:1");
  CHECK(sourceIdentity("images:frames/../run1?rate=5") == "images:" + cwd + "/run1");
  CHECK(sourceIdentity("run1") == "images:" + cwd + "/run1");
  CHECK(sourceIdentity("video:/data/clip.mp4?rate=30") == "video:/data/clip.mp4");
  CHECK(sourceIdentity("IMAGES:/data/run1") == "images:/data/run1");
}
