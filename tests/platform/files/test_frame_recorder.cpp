// FrameRecorder (platform/files): what `toposlam capture --record` writes plays back through images:
// with the same frames and timestamps; a folder holding a recording is refused; the size bound holds.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/io/frame_recorder.hpp"
#include "toposlam/io/source_factory.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

fs::path freshFolder(const std::string& name) {
  const fs::path dir = fs::path(TOPOSLAM_BINARY_DIR) / "tests" / "io" / name;
  fs::remove_all(dir);
  return dir;
}

Frame frameAt(std::int64_t sequence, double timestamp_s) {
  Frame frame;
  frame.sequence = sequence;
  frame.timestamp_s = timestamp_s;
  frame.image = cv::Mat(48, 64, CV_8UC3, cv::Scalar(static_cast<double>(40 * sequence), 90.0, 200.0));
  frame.image(cv::Rect(static_cast<int>(8 * sequence), 4, 12, 40)).setTo(cv::Scalar(255, 255, 255));  // a bar that moves
  return frame;
}

}  // namespace

TEST_CASE("GIVEN frames recorded as PNG WHEN played back through images: THEN frames and timestamps are the same",
          "[io][record]") {
  const fs::path dir = freshFolder("record-png");
  const double times[] = {1000.125, 1000.375, 1001.0};  // 0.25 s then 0.625 s apart: not a fixed rate
  {
    FrameRecorder recorder(dir, FrameRecorderConfig{"png", 95, 1u << 20});
    for (int i = 0; i < 3; ++i) CHECK(recorder.record(frameAt(i, times[i])));
    recorder.finish();
    CHECK(recorder.frames() == 3);
    CHECK(recorder.bytes() == fs::file_size(dir / "000000.png") + fs::file_size(dir / "000001.png") +
                                  fs::file_size(dir / "000002.png"));
  }
  std::ifstream table(dir / "timestamps.csv");
  std::stringstream text;
  text << table.rdbuf();
  CHECK(text.str() == "name,time_s\n000000.png,1000.125000\n000001.png,1000.375000\n000002.png,1001.000000\n");

  const std::unique_ptr<FrameSource> replay = openFrameSource("images:" + dir.string());
  CHECK_THAT(replay->describe(), Catch::Contains("times from " + (dir / "timestamps.csv").string()));
  for (int i = 0; i < 3; ++i) {
    const std::optional<Frame> frame = replay->next();
    REQUIRE(frame.has_value());
    CHECK(frame->timestamp_s == Approx(times[i]).margin(1e-9));
    CHECK(cv::norm(frame->image, frameAt(i, times[i]).image, cv::NORM_INF) == 0.0);  // PNG: lossless
  }
  CHECK_FALSE(replay->next().has_value());
  // ?rate=recorded paces by those timestamps and says so.
  CHECK_THAT(openFrameSource("images:" + dir.string() + "?rate=recorded")->describe(),
             Catch::EndsWith("at the recorded rate (frame timestamps)"));
}

TEST_CASE("GIVEN a folder that holds a recording WHEN recording into it again THEN it is refused, naming it",
          "[io][record]") {
  const fs::path dir = freshFolder("record-twice");
  {
    FrameRecorder recorder(dir, {});
    CHECK(recorder.record(frameAt(0, 0.0)));
    recorder.finish();
  }
  CHECK_THROWS_WITH(FrameRecorder(dir, {}), Catch::Contains(dir.string() + " already holds a recording"));
  CHECK_THROWS_WITH(FrameRecorder(freshFolder("record-bad"), FrameRecorderConfig{"gif", 95, 1}),
                    Catch::Contains("format 'gif' is not jpg or png"));
}

TEST_CASE("GIVEN a size bound WHEN frames exceed it THEN the recorder stops at the last frame that fits",
          "[io][record]") {
  const fs::path dir = freshFolder("record-bound");
  FrameRecorder probe(freshFolder("record-probe"), FrameRecorderConfig{"png", 95, 1u << 20});
  REQUIRE(probe.record(frameAt(0, 0.0)));
  const std::uint64_t one = probe.bytes();
  // Room for two frames of about that size, not three.
  FrameRecorder recorder(dir, FrameRecorderConfig{"png", 95, 2 * one + one / 2});
  int kept = 0;
  for (int i = 0; i < 5; ++i) kept += recorder.record(frameAt(0, 0.1 * i)) ? 1 : 0;
  recorder.finish();
  CHECK(kept == 2);
  CHECK(recorder.full());
  CHECK(recorder.bytes() == 2 * one);
  CHECK_FALSE(fs::exists(dir / "000002.png"));
  CHECK(openFrameSource("images:" + dir.string())->frameCountHint() == 2);
}

namespace {

/// Frames with the given timestamps, at once.
class ListedTimesSource final : public FrameSource {
 public:
  explicit ListedTimesSource(std::vector<double> times) : times_(std::move(times)) {}
  std::string describe() const override { return "listed times"; }
  std::optional<Frame> next() override {
    if (next_ >= times_.size()) return std::nullopt;
    Frame frame = frameAt(static_cast<std::int64_t>(next_), times_[next_]);
    ++next_;
    return frame;
  }
  void interrupt() override {}

 private:
  std::vector<double> times_;
  std::size_t next_ = 0;
};

}  // namespace

TEST_CASE(
    "GIVEN a recording whose clock steps back 30 s WHEN played at the recorded rate THEN the frame after the "
    "step comes one frame interval later, not at once, and keeps its timestamp",
    "[io][record][reliability]") {
  // 0.4 s apart; the third frame's clock stepped back 30 s (docs/reliability.md, "Clock jumps").
  const std::unique_ptr<FrameSource> replay =
      makeRecordedRateSource(std::make_unique<ListedTimesSource>(std::vector<double>{100.0, 100.4, 70.8, 71.2}));
  std::vector<double> delivered_at, stamps;
  const auto start = std::chrono::steady_clock::now();
  while (std::optional<Frame> frame = replay->next()) {
    delivered_at.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    stamps.push_back(frame->timestamp_s);
  }
  REQUIRE(delivered_at.size() == 4);
  CHECK(stamps == std::vector<double>{100.0, 100.4, 70.8, 71.2});
  // Lower bounds only (a slow machine delivers later, never earlier): before, the frame after the step was
  // due at once, with the frame before it.
  CHECK(delivered_at[2] - delivered_at[1] >= 0.35);
  CHECK(delivered_at[3] - delivered_at[2] >= 0.35);
  CHECK(delivered_at[3] >= 1.15);
}
