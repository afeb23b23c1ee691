// Tests of the frame sources and the factory: the bundled samples in natural order, a truncated JPEG
// skipped and counted, the sim: source, plain paths, video files, the scheme registry, bad URIs.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>

#include <unistd.h>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "test_files.hpp"
#include "toposlam/io/file_sources.hpp"
#include "toposlam/io/sim_source.hpp"
#include "toposlam/io/source_factory.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

const std::string kSamples = std::string(TOPOSLAM_SAMPLES_DIR) + "/samples";

using test::TempFolder;

std::vector<char> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// DIR/<prefix><i><extension>; appended piecewise: GCC 12 warns falsely (-Wrestrict) on "literal" +
// std::string.
fs::path numbered(const fs::path& dir, const char* prefix, int i, const char* extension) {
  std::string name(prefix);
  name.append(std::to_string(i)).append(extension);
  return dir / name;
}

std::string openError(const std::string& uri) {
  try {
    openFrameSource(uri);
  } catch (const FrameSourceError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("GIVEN the bundled sample folder WHEN played as images: THEN 1.jpg..84.jpg come in natural order", "[io]") {
  std::unique_ptr<FrameSource> source = openFrameSource("images:" + kSamples);
  CHECK(source->frameCountHint() == 84);
  CHECK_THAT(source->describe(), Catch::Contains("84 frames"));
  int count = 0;
  while (std::optional<Frame> frame = source->next()) {
    ++count;
    CHECK(frame->name == std::to_string(count) + ".jpg");
    CHECK(frame->sequence == count - 1);
    CHECK(frame->timestamp_s == Approx(count - 1.0));  // 1 Hz by default
    CHECK(frame->image.type() == CV_8UC3);
    CHECK(frame->image.size() == cv::Size(512, 384));
  }
  CHECK(count == 84);
  CHECK(source->skippedFrames() == 0);

  // A plain folder path means images:, and a glob selects files, still in natural order.
  std::unique_ptr<FrameSource> plain = openFrameSource(kSamples);
  CHECK(plain->frameCountHint() == 84);
  std::unique_ptr<FrameSource> glob = openFrameSource("images:" + kSamples + "/?.jpg?rate=1000");
  std::vector<std::string> names;
  std::vector<double> times;
  while (std::optional<Frame> frame = glob->next()) {
    names.push_back(frame->name);
    times.push_back(frame->timestamp_s);
  }
  CHECK(names == std::vector<std::string>{"1.jpg", "2.jpg", "3.jpg", "4.jpg", "5.jpg", "6.jpg", "7.jpg", "8.jpg", "9.jpg"});
  CHECK(times[3] == Approx(3.0 / 1000));  // timestamps follow the rate
}

TEST_CASE("GIVEN a folder with a truncated JPEG and a junk PNG WHEN played THEN both are skipped and counted", "[io]") {
  TempFolder folder("truncated");
  fs::copy_file(kSamples + "/1.jpg", folder.path / "1.jpg");
  const std::vector<char> bytes = readBytes(kSamples + "/2.jpg");
  std::ofstream(folder.path / "2.jpg", std::ios::binary).write(bytes.data(), static_cast<long>(bytes.size() / 2));
  std::ofstream(folder.path / "3.png", std::ios::binary) << "this is not a png at all, just text";
  fs::copy_file(kSamples + "/4.jpg", folder.path / "10.jpg");
  std::ofstream(folder.path / "notes.txt") << "ignored: not an image";

  std::unique_ptr<FrameSource> source = openFrameSource(folder.path.string());
  CHECK(source->frameCountHint() == 4);
  std::vector<std::string> names;
  std::vector<std::int64_t> sequences;
  while (std::optional<Frame> frame = source->next()) {
    names.push_back(frame->name);
    sequences.push_back(frame->sequence);
  }
  CHECK(names == std::vector<std::string>{"1.jpg", "10.jpg"});
  CHECK(sequences == std::vector<std::int64_t>{0, 3});  // the gap shows the skipped files
  CHECK(source->skippedFrames() == 2);

  CHECK_FALSE(imageBytesLookComplete(std::vector<unsigned char>(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() / 2))));
  CHECK(imageBytesLookComplete(std::vector<unsigned char>(bytes.begin(), bytes.end())));
}

TEST_CASE(
    "GIVEN a folder of 51 bad files of four kinds WHEN played THEN each is counted by its reason, and the "
    "log "
    "names the first 5 and sums up the rest in one line",
    "[io][reliability]") {
  TempFolder folder("bad-kinds");
  fs::copy_file(kSamples + "/1.jpg", folder.path / "0000.jpg");
  const std::vector<char> jpeg = readBytes(kSamples + "/2.jpg");
  // 40 tiny JPEGs cut after 100 bytes (no end marker) and 5 empty files: truncated.
  for (int i = 0; i < 40; ++i)
    std::ofstream(numbered(folder.path, "t", i, ".jpg"), std::ios::binary).write(jpeg.data(), 100);
  for (int i = 0; i < 5; ++i) std::ofstream(numbered(folder.path, "e", i, ".jpg"), std::ios::binary);
  // 3 JPEGs with their middle overwritten (header and end marker intact): corrupt.
  for (int i = 0; i < 3; ++i) {
    std::vector<char> damaged = jpeg;
    for (std::size_t b = damaged.size() / 4; b < damaged.size() * 3 / 4; ++b)
      damaged[b] = static_cast<char>(b * 7 + 1);
    std::ofstream(numbered(folder.path, "c", i, ".jpg"), std::ios::binary)
        .write(damaged.data(), static_cast<long>(damaged.size()));
  }
  // 2 PNGs whose header claims 65000 x 65000 pixels: too large, not decoded.
  std::vector<unsigned char> png;
  cv::imencode(".png", cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3)), png);
  for (int at : {16, 20}) {  // IHDR width and height, big-endian
    png[static_cast<std::size_t>(at) + 2] = 0xFD;
    png[static_cast<std::size_t>(at) + 3] = 0xE8;
  }
  for (int i = 0; i < 2; ++i)
    std::ofstream(numbered(folder.path, "l", i, ".png"), std::ios::binary)
        .write(reinterpret_cast<const char*>(png.data()), static_cast<long>(png.size()));
  // 1 file gone between the listing and its reading: unreadable.
  std::ofstream(folder.path / "u.jpg", std::ios::binary).write(jpeg.data(), static_cast<long>(jpeg.size()));

  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  sink->set_pattern("%l %v");
  const std::shared_ptr<spdlog::logger> previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("bad-kinds", sink));
  std::int64_t frames = 0;
  SkippedFrames skipped;
  {
    std::unique_ptr<FrameSource> source = openFrameSource(folder.path.string());
    REQUIRE(source->frameCountHint() == 52);
    fs::remove(folder.path / "u.jpg");
    while (source->next()) ++frames;
    skipped = source->skippedByReason();
    CHECK(source->skippedFrames() == 51);
  }
  spdlog::set_default_logger(previous);

  CHECK(frames == 1);
  CHECK(skipped.total() == 51);
  CHECK(skipped[SkipReason::Truncated] == 45);
  CHECK(skipped[SkipReason::Corrupt] == 3);
  CHECK(skipped[SkipReason::TooLarge] == 2);
  CHECK(skipped[SkipReason::Unreadable] == 1);
  CHECK(skipped[SkipReason::Other] == 0);
  CHECK(skippedFramesText(skipped) ==
        "skipped 51 frames (unreadable 1, truncated 45, corrupt 3, too large 2)");
  // The log: 5 files named, then summaries; the last (at the end of the folder) says 51 in all.
  std::istringstream lines(log.str());
  std::vector<std::string> named, summaries;
  for (std::string line; std::getline(lines, line);) {
    INFO(line);
    if (line.rfind("warning images: skipping bad files: ", 0) == 0)
      summaries.push_back(line);
    else if (line.rfind("warning images: skipping ", 0) == 0)
      named.push_back(line);
  }
  INFO(log.str());
  CHECK(named.size() == 5);
  CHECK_THAT(named.back(),
             Catch::EndsWith("(images: skipping bad files: further ones are counted and summarised)"));
  REQUIRE_FALSE(summaries.empty());
  CHECK(summaries.size() <= 2);  // one, unless the test stalled for 10 s between two files
  CHECK_THAT(summaries.back(), Catch::EndsWith("more suppressed (51 in all)"));
  if (summaries.size() == 1)
    CHECK(summaries[0] == "warning images: skipping bad files: 46 more suppressed (51 in all)");
}

TEST_CASE("GIVEN the last frame a map holds WHEN an image folder continues after it THEN the earlier files are "
          "skipped, also when files were added before it, and an unknown file starts over", "[io][reliability]") {
  TempFolder folder("continue");
  for (int i : {1, 2, 3, 4, 5}) {
    const std::string name = std::to_string(i) + ".jpg";
    fs::copy_file(kSamples + "/" + name, folder.path / name);
  }
  auto sequences = [](FrameSource& source) {
    std::vector<std::int64_t> out;
    while (std::optional<Frame> frame = source.next()) out.push_back(frame->sequence);
    return out;
  };
  {
    std::unique_ptr<FrameSource> source = openFrameSource("images:" + folder.path.string() + "?rate=1000");
    CHECK(source->frameName(2) == "3.jpg");
    CHECK(source->frameName(5).empty());
    CHECK(source->frameName(-1).empty());
    CHECK(source->continueAfter(2, "3.jpg") == std::optional<std::int64_t>(3));  // through the rate limiter
    CHECK(sequences(*source) == std::vector<std::int64_t>{3, 4});
  }
  {
    // A file added before it: the same file, now number 3, is found by its name.
    fs::copy_file(kSamples + "/9.jpg", folder.path / "0.jpg");
    std::unique_ptr<FrameSource> source = openFrameSource("images:" + folder.path.string());
    CHECK(source->continueAfter(2, "3.jpg") == std::optional<std::int64_t>(4));
    CHECK(sequences(*source) == std::vector<std::int64_t>{4, 5});
  }
  {
    // Every frame mapped: nothing left. No such file, or no name recorded: the source starts over.
    std::unique_ptr<FrameSource> done = openFrameSource("images:" + folder.path.string());
    CHECK(done->continueAfter(5, "5.jpg") == std::optional<std::int64_t>(6));
    CHECK(sequences(*done).empty());
    std::unique_ptr<FrameSource> other = openFrameSource("images:" + folder.path.string());
    CHECK_FALSE(other->continueAfter(2, "b3.jpg").has_value());
    CHECK_FALSE(other->continueAfter(2, "").has_value());
    CHECK(sequences(*other).size() == 6);
  }
  // Live sources cannot continue (the default).
  std::unique_ptr<FrameSource> sim = openFrameSource("sim:office?size=160x120");
  CHECK_FALSE(sim->continueAfter(10, "x").has_value());
  CHECK(sim->frameName(0).empty());
}

TEST_CASE("GIVEN a sim: URI WHEN opened THEN frames come at the simulated time with ground truth", "[io]") {
  std::unique_ptr<FrameSource> source = openFrameSource("sim:office?route=loop2&fps=5&size=320x240&seed=1");
  CHECK(source->frameCountHint() > 1000);
  CHECK_THAT(source->describe(), Catch::Contains("office") && Catch::Contains("loop2"));
  auto* sim_source = dynamic_cast<SimFrameSource*>(source.get());
  REQUIRE(sim_source != nullptr);
  for (int i = 0; i < 3; ++i) {
    std::optional<Frame> frame = source->next();
    REQUIRE(frame);
    CHECK(frame->image.size() == cv::Size(320, 240));
    CHECK(frame->timestamp_s == Approx(i / 5.0));
    CHECK(frame->sequence == i);
    CHECK(sim_source->lastTruth().frame == i);
    CHECK(sim_source->lastTruth().room == 0);  // the route starts in the corridor
  }
  // Variation switches are query keys.
  const sim::SimConfig config =
      simConfigFromUri(parseSourceUri("sim:home?light=night&noise=2.5&people=3&pitch=1.5&moved=1&speed=0.3&fov=70"));
  CHECK(config.world == "home");
  CHECK(config.lighting == sim::LightingMode::Night);
  CHECK(config.noise_sigma == 2.5);
  CHECK(config.people == 3);
  CHECK(config.pitch_deg == 1.5);
  CHECK(config.moved_furniture);
  CHECK(config.motion.speed == 0.3);
  CHECK(config.camera.horizontal_fov_deg == 70);
}

TEST_CASE("GIVEN bad URIs WHEN opened THEN the errors name the problem and what is allowed", "[io]") {
  const std::string unknown = openError("foo:bar");
  CHECK_THAT(unknown, Catch::Contains("unknown scheme 'foo:'") && Catch::Contains("images:") && Catch::Contains("sim:"));
  CHECK_THAT(openError("sim:office?bogus=1"), Catch::Contains("bogus") && Catch::Contains("route"));
  CHECK_THAT(openError("sim:office?route=nope"), Catch::Contains("nope") && Catch::Contains("loop2"));
  CHECK_THAT(openError("sim:office?size=12x"), Catch::Contains("size=12x"));
  CHECK_THAT(openError("sim:office?light=dusk"), Catch::Contains("light=dusk") && Catch::Contains("night"));
  CHECK_THAT(openError("sim:castle"), Catch::Contains("castle") && Catch::Contains("office"));
  CHECK_THAT(openError("sim:"), Catch::Contains("world"));
  CHECK_THAT(openError("images:/nonexistent/folder"), Catch::Contains("/nonexistent/folder"));
  CHECK_THAT(openError("images:" + kSamples + "?fps=0"), Catch::Contains("fps=0"));
  CHECK_THAT(openError("images:" + kSamples + "?speed=3"), Catch::Contains("speed"));
  CHECK_THAT(openError("images:" + kSamples + "?rate=0"), Catch::Contains("rate=0"));
  CHECK_THAT(openError("video:/nonexistent.mp4"), Catch::Contains("/nonexistent.mp4"));
  CHECK_THAT(openError("/nonexistent/thing"), Catch::Contains("/nonexistent/thing") && Catch::Contains("images:"));
  TempFolder empty("empty");
  CHECK_THAT(openError(empty.path.string()), Catch::Contains("no .png/.jpg"));
}

TEST_CASE("GIVEN a registered scheme WHEN opened THEN the factory calls its opener with the parsed URI", "[io]") {
  registerFrameSourceScheme("test-scheme", [](const SourceUri& uri) -> std::unique_ptr<FrameSource> {
    uri.requireOnly({"size"});
    const auto [width, height] = uri.getSize("size", {32, 24}, 1, 100);
    (void)height;
    return std::make_unique<ImageFilesSource>(uri.path + "/" + std::to_string(width) + ".jpg");
  }, "test-scheme:FOLDER?size=WxH");
  std::unique_ptr<FrameSource> source = openFrameSource("test-scheme:" + kSamples + "?size=7x7");
  std::optional<Frame> frame = source->next();
  REQUIRE(frame);
  CHECK(frame->name == "7.jpg");
  CHECK_FALSE(source->next());
  CHECK_THAT(openError("test-scheme:" + kSamples + "?colour=1"), Catch::Contains("colour"));
  bool listed = false;
  for (const auto& [scheme, usage] : registeredFrameSourceSchemes()) listed |= scheme == "test-scheme";
  CHECK(listed);
  CHECK_THROWS_AS(registerFrameSourceScheme("Bad Scheme", nullptr, ""), FrameSourceError);
}

TEST_CASE("GIVEN a short video file WHEN played THEN its frames come out in order", "[io]") {
  TempFolder folder("video");
  const fs::path path = folder.path / "clip.avi";
  cv::VideoWriter writer(path.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(64, 48));
  if (!writer.isOpened()) {
    WARN("this OpenCV cannot write MJPG AVI files; video: test skipped");
    return;
  }
  for (int i = 0; i < 5; ++i) writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(i * 50, 100, 200 - i * 40)));
  writer.release();
  for (const std::string& uri : {"video:" + path.string(), path.string()}) {
    std::unique_ptr<FrameSource> source = openFrameSource(uri);
    int count = 0;
    while (std::optional<Frame> frame = source->next()) {
      CHECK(frame->image.size() == cv::Size(64, 48));
      CHECK(frame->timestamp_s == Approx(count / 10.0));
      CHECK(std::abs(frame->image.at<cv::Vec3b>(24, 32)[0] - count * 50) < 12);
      ++count;
    }
    CHECK(count == 5);
  }
}

SCENARIO("GIVEN the simulator and an image folder WHEN asked their state THEN they say what they are, not a camera") {
  SimFrameSource sim(simConfigFromUri(parseSourceUri("sim:office?size=64x48")));
  CHECK(sim.state().kind == SourceKind::Simulator);
  ImageFilesSource images(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples", 1.0);
  CHECK(images.state().kind == SourceKind::ImageFiles);
}

SCENARIO("GIVEN source URIs with a bad option WHEN checked without opening THEN the opener's refusal comes, "
         "naming the key") {
  CHECK_NOTHROW(checkFrameSourceUri("sim:office?fps=5"));
  CHECK_NOTHROW(checkFrameSourceUri("images:/nonexistent/folder?fps=2"));  // nothing is opened
  CHECK_THROWS_WITH(checkFrameSourceUri("sim:office?fps=fast"), Catch::Contains("fps"));
  CHECK_THROWS_WITH(checkFrameSourceUri("images:/x?speed=2"), Catch::Contains("speed"));
  CHECK_THROWS_WITH(checkFrameSourceUri("video:/x.mp4?rate=0"), Catch::Contains("rate"));
  CHECK_THROWS_WITH(checkFrameSourceUri("bogus:thing"), Catch::Contains("unknown scheme 'bogus:'"));
}
