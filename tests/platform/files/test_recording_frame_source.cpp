// RecordingFrameSource (platform/files): frames pass through unchanged and in order whatever the writer does;
// a writer that is behind loses recorded copies (dropped oldest, counted), never pipeline frames; the frames
// that are written play back through images: with their timestamps.
#include <catch2/catch.hpp>

#include <filesystem>
#include <memory>
#include <thread>

#include <opencv2/core.hpp>

#include "toposlam/io/recording_frame_source.hpp"
#include "toposlam/io/source_factory.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

/// `count` frames, 0.1 s apart, each a different grey.
class CountingSource final : public FrameSource {
 public:
  explicit CountingSource(int count) : count_(count) {}
  std::string describe() const override { return "counting"; }
  std::optional<Frame> next() override {
    if (next_ >= count_) return std::nullopt;
    Frame f;
    f.sequence = next_;
    f.timestamp_s = 0.1 * next_;
    f.image = cv::Mat(24, 32, CV_8UC3, cv::Scalar::all(static_cast<double>(5 * next_)));
    ++next_;
    return f;
  }
  void interrupt() override {}

 private:
  int count_;
  int next_ = 0;
};

fs::path freshFolder(const std::string& name) {
  const fs::path dir = fs::path(TOPOSLAM_BINARY_DIR) / "tests" / "io" / name;
  fs::remove_all(dir);
  return dir;
}

}  // namespace

TEST_CASE("GIVEN a writer that has not started WHEN 20 frames pass with a queue of 4 THEN every frame passes "
          "and the writer gets the newest 4, 16 dropped and counted",
          "[io][record]") {
  const fs::path dir = freshFolder("recording-source-behind");
  RecordingFrameSource source(std::make_unique<CountingSource>(20),
                              std::make_unique<FrameRecorder>(dir, FrameRecorderConfig{"png", 95, 1u << 20}), 4);
  int passed = 0;
  for (std::optional<Frame> f; (f = source.next()); ++passed) {
    CHECK(f->sequence == passed);                                 // unchanged, in order
    CHECK(f->image.at<cv::Vec3b>(0, 0)[0] == 5 * passed);
  }
  CHECK(passed == 20);
  source.closeWriter();
  source.runWriter();  // drains what is queued, then ends
  const RecordingStatus s = source.status();
  CHECK(s.state == RecordingState::Finished);
  CHECK(s.offered == 20);
  CHECK(s.dropped == 16);
  CHECK(s.written == 4);
  auto replay = openFrameSource("images:" + dir.string());
  std::vector<double> times;
  std::vector<int> greys;
  for (std::optional<Frame> f; (f = replay->next());) {
    times.push_back(f->timestamp_s);
    greys.push_back(f->image.at<cv::Vec3b>(0, 0)[0]);
  }
  CHECK(times == std::vector<double>{1.6, 1.7, 1.8, 1.9});  // frames 16..19, their own timestamps
  CHECK(greys == std::vector<int>{80, 85, 90, 95});
}

TEST_CASE("GIVEN a writer on its own thread WHEN the size bound is reached THEN recording stops as Full and the "
          "frames still pass",
          "[io][record]") {
  const fs::path dir = freshFolder("recording-source-full");
  // PNG of a flat 32x24 image: well under 1 kB each; a 2 kB bound holds a few.
  RecordingFrameSource source(std::make_unique<CountingSource>(200),
                              std::make_unique<FrameRecorder>(dir, FrameRecorderConfig{"png", 95, 2000}), 256);
  std::thread writer([&] { source.runWriter(); });
  int passed = 0;
  while (source.next()) ++passed;
  source.closeWriter();
  writer.join();
  const RecordingStatus s = source.status();
  CHECK(passed == 200);
  CHECK(s.state == RecordingState::Full);
  CHECK(s.written >= 1);
  CHECK(s.bytes <= 2000u);
  CHECK(s.written < 200);
  CHECK(s.dropped == 0);
}

TEST_CASE("GIVEN a recordings folder WHEN a new recording folder is named THEN it is the UTC time, made unique",
          "[io][record]") {
  const fs::path dir = freshFolder("recording-names");
  CHECK(newRecordingFolder(dir, 1796198400) == dir / "20261202T080000Z");
  fs::create_directories(dir / "20261202T080000Z");
  CHECK(newRecordingFolder(dir, 1796198400) == dir / "20261202T080000Z-2");
  CHECK(bytesUnder(dir / "absent") == 0u);
}
