// V4l2FrameSource against a scripted fake driver: negotiation, conversion, zero-copy leases and every
// error path (EAGAIN, EINTR, ENODEV mid-stream, a driver that changes the format, short and
// error-flagged buffers, sequence gaps, undecodable MJPEG, unplug and reconnect with backoff).
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "fake_v4l2_device.hpp"
#include "toposlam/io/source_factory.hpp"
#include "v4l2_frame_source.hpp"

using toposlam::FrameSourceError;
using toposlam::SkippedFrames;
using toposlam::SkipReason;
using toposlam::V4l2FrameSource;
using toposlam::V4l2PixelFormat;
using toposlam::V4l2SourceConfig;
using toposlam::test::FakeV4l2Event;
using toposlam::test::FakeV4l2State;
using Kind = FakeV4l2Event::Kind;

namespace {

constexpr int kWidth = 32;
constexpr int kHeight = 16;

V4l2SourceConfig smallConfig(V4l2PixelFormat format = V4l2PixelFormat::Yuyv) {
  V4l2SourceConfig config;
  config.device = "/dev/video7";
  config.width = kWidth;
  config.height = kHeight;
  config.format = format;
  config.reconnect_initial_ms = 100;
  config.reconnect_max_ms = 400;
  return config;
}

/// A YUYV image of one colour (Y, U, V), `width` x `height`.
std::vector<std::uint8_t> yuyv(int width, int height, std::uint8_t y, std::uint8_t u, std::uint8_t v) {
  std::vector<std::uint8_t> bytes;
  for (int i = 0; i < width * height / 2; ++i) {
    bytes.insert(bytes.end(), {y, u, y, v});
  }
  return bytes;
}

FakeV4l2Event frameEvent(std::vector<std::uint8_t> payload, std::uint32_t sequence,
                         double timestamp_s = 0.0) {
  FakeV4l2Event event;
  event.kind = Kind::Frame;
  event.payload = std::move(payload);
  event.sequence = sequence;
  event.timestamp_s = timestamp_s;
  return event;
}

FakeV4l2Event errorEvent(Kind kind, int error = 0) {
  FakeV4l2Event event;
  event.kind = kind;
  event.error = error;
  return event;
}

struct Rig {
  FakeV4l2State state;
  std::vector<std::chrono::milliseconds> sleeps;
  double clock_s = 1000.0;
  std::function<void()> during_sleep;
  std::unique_ptr<V4l2FrameSource> source;

  void open(const V4l2SourceConfig& config) {
    toposlam::V4l2Runtime runtime;
    runtime.monotonic_s = [this] { return clock_s; };
    runtime.sleep = [this](std::chrono::milliseconds delay) {
      sleeps.push_back(delay);
      if (during_sleep) during_sleep();
    };
    source = std::make_unique<V4l2FrameSource>(
        config, std::make_unique<toposlam::test::FakeV4l2Device>(state), runtime);
    state.on_idle = [this] { source->interrupt(); };
  }
  /// All frames until the script runs out.
  std::vector<toposlam::Frame> drain() {
    std::vector<toposlam::Frame> frames;
    while (auto frame = source->next()) frames.push_back(std::move(*frame));
    return frames;
  }
};

}  // namespace

SCENARIO("GIVEN a YUYV driver WHEN frames arrive THEN they come out as BGR with sequence and timestamps") {
  Rig rig;
  rig.open(smallConfig());
  REQUIRE(rig.state.streamons == 1);
  REQUIRE(rig.state.queued.size() == 4);
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 235, 128, 128), 0, 12.5));   // white
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 16, 128, 128), 1, 12.533));  // black
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 81, 90, 240), 2, 12.566));   // BT.601 red
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 3);
  CHECK(frames[0].image.type() == CV_8UC3);
  CHECK(frames[0].image.cols == kWidth);
  CHECK(frames[0].image.rows == kHeight);
  CHECK(frames[0].image.at<cv::Vec3b>(5, 7) == cv::Vec3b(255, 255, 255));
  CHECK(frames[1].image.at<cv::Vec3b>(5, 7) == cv::Vec3b(0, 0, 0));
  const cv::Vec3b red = frames[2].image.at<cv::Vec3b>(3, 3);
  CHECK(red[0] <= 2);
  CHECK(red[1] <= 2);
  CHECK(red[2] >= 250);
  CHECK(frames[0].sequence == 0);
  CHECK(frames[2].sequence == 2);
  CHECK(frames[0].timestamp_s == Approx(12.5).margin(1e-6));
  CHECK(frames[1].timestamp_s == Approx(12.533).margin(1e-6));
  THEN("each buffer went back to the driver right after conversion (no lease held)") {
    CHECK_FALSE(frames[0].buffer_lease);
    CHECK(rig.state.qbufs == 4 + 3);
    CHECK(rig.source->droppedFrames() == 0);
    CHECK(rig.source->skippedFrames() == 0);
    CHECK(rig.source->status().frames == 3);
  }
}

SCENARIO(
    "GIVEN a driver without monotonic timestamps WHEN a frame arrives THEN the injected clock stamps it") {
  Rig rig;
  rig.state.monotonic_timestamps = false;
  rig.open(smallConfig());
  rig.clock_s = 77.25;
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 100, 128, 128), 0, 5.0));
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].timestamp_s == 77.25);
}

SCENARIO("GIVEN EAGAIN, EINTR and poll timeouts WHEN capturing THEN they are retried without loss") {
  Rig rig;
  rig.open(smallConfig());
  rig.state.events.push_back(errorEvent(Kind::PollError, EINTR));
  rig.state.events.push_back(errorEvent(Kind::PollTimeout));
  rig.state.events.push_back(errorEvent(Kind::DqbufError, EAGAIN));
  rig.state.events.push_back(errorEvent(Kind::DqbufError, EINTR));
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0));
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 1));
  const auto frames = rig.drain();
  CHECK(frames.size() == 2);
  const auto status = rig.source->status();
  CHECK(status.connected);
  CHECK(status.reconnects == 0);
  CHECK(status.dropped == 0);
  CHECK(status.skipped == 0);
  CHECK(rig.state.opens == 1);
}

SCENARIO(
    "GIVEN driver sequence gaps WHEN capturing THEN the gaps are counted as drops and kept in "
    "Frame::sequence") {
  Rig rig;
  rig.open(smallConfig());
  for (std::uint32_t sequence : {10U, 11U, 14U, 15U, 20U})
    rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), sequence));
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 5);
  CHECK(frames[0].sequence == 0);  // numbering starts at 0 whatever the driver's first number
  CHECK(frames[1].sequence == 1);
  CHECK(frames[2].sequence == 4);
  CHECK(frames[4].sequence == 10);
  CHECK(rig.source->droppedFrames() == 2 + 4);
  CHECK(rig.source->state().dropped == 2 + 4);  // what the pipeline's status shows
}

SCENARIO(
    "GIVEN a driver whose first buffer is stale (v4l2loopback) WHEN capturing THEN that jump is not a drop") {
  Rig rig;
  rig.open(smallConfig());
  for (std::uint32_t sequence : {0U, 725U, 726U, 728U})
    rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), sequence));
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 4);
  CHECK(frames[1].sequence == 1);
  CHECK(frames[2].sequence == 2);
  CHECK(frames[3].sequence == 4);
  CHECK(rig.source->droppedFrames() == 1);
}

SCENARIO("GIVEN error-flagged and short buffers WHEN capturing THEN they are skipped, counted and requeued") {
  Rig rig;
  rig.open(smallConfig());
  auto flagged = frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0);
  flagged.flags = V4L2_BUF_FLAG_ERROR;
  auto truncated = frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 1);
  truncated.bytesused = kWidth * kHeight * 2 - 64;  // two lines missing
  rig.state.events.push_back(flagged);
  rig.state.events.push_back(truncated);
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 2));
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].sequence == 2);
  const auto status = rig.source->status();
  CHECK(status.skipped == 2);
  CHECK(status.error_buffers == 1);
  CHECK(status.short_buffers == 1);
  CHECK(status.dropped == 0);           // skipped is not dropped
  CHECK(rig.state.queued.size() == 4);  // every buffer is back with the driver
  // By reason, as the status message publishes them.
  const SkippedFrames by_reason = rig.source->skippedByReason();
  CHECK(by_reason[SkipReason::DeviceError] == 1);
  CHECK(by_reason[SkipReason::Truncated] == 1);
  CHECK(by_reason.total() == 2);
}

SCENARIO(
    "GIVEN an MJPEG driver WHEN one frame decodes and one is garbage THEN the garbage is skipped and "
    "counted") {
  Rig rig;
  rig.state.offered = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV};
  rig.open(smallConfig(V4l2PixelFormat::Mjpeg));
  cv::Mat picture(kHeight, kWidth, CV_8UC3, cv::Scalar(0, 0, 200));
  std::vector<std::uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", picture, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  REQUIRE(jpeg.size() <= static_cast<std::size_t>(kWidth * kHeight * 2));
  rig.state.events.push_back(frameEvent(jpeg, 0));
  std::vector<std::uint8_t> garbage(300, 0x5a);
  rig.state.events.push_back(frameEvent(garbage, 1));
  auto empty = frameEvent({}, 2);
  rig.state.events.push_back(empty);
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].image.cols == kWidth);
  const cv::Vec3b pixel = frames[0].image.at<cv::Vec3b>(8, 16);
  CHECK(pixel[2] >= 190);
  CHECK(pixel[0] <= 10);
  const auto status = rig.source->status();
  CHECK(status.decode_failures == 1);
  CHECK(status.short_buffers == 1);
  CHECK(status.skipped == 2);
  CHECK(rig.state.queued.size() == 4);
  const SkippedFrames by_reason = rig.source->skippedByReason();
  CHECK(by_reason[SkipReason::Corrupt] == 1);    // the garbage
  CHECK(by_reason[SkipReason::Truncated] == 1);  // the empty buffer
  CHECK(by_reason.total() == 2);
}

SCENARIO(
    "GIVEN a driver that changes the requested format WHEN opening THEN its choice is used or clearly "
    "refused") {
  WHEN("it picks another size") {
    Rig rig;
    rig.state.forced_width = 64;
    rig.state.forced_height = 24;
    rig.open(smallConfig());
    rig.state.events.push_back(frameEvent(yuyv(64, 24, 235, 128, 128), 0));
    const auto frames = rig.drain();
    REQUIRE(frames.size() == 1);
    CHECK(frames[0].image.cols == 64);
    CHECK(frames[0].image.rows == 24);
    CHECK(rig.source->status().width == 64);
  }
  WHEN("it switches to another format toposlam converts (GREY)") {
    Rig rig;
    rig.state.offered = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY};
    rig.state.forced_format = V4L2_PIX_FMT_GREY;
    rig.open(smallConfig());
    rig.state.events.push_back(frameEvent(std::vector<std::uint8_t>(kWidth * kHeight, 77), 0));
    const auto frames = rig.drain();
    REQUIRE(frames.size() == 1);
    CHECK(frames[0].image.at<cv::Vec3b>(1, 1) == cv::Vec3b(77, 77, 77));
    CHECK(rig.source->status().pixel_format == "GREY");
  }
  WHEN("it switches to a format toposlam cannot convert (NV12)") {
    Rig rig;
    rig.state.forced_format = V4L2_PIX_FMT_NV12;
    REQUIRE_THROWS_WITH(rig.open(smallConfig()),
                        Catch::Contains("chose pixel format NV12") && Catch::Contains("/dev/video7"));
    CHECK_FALSE(rig.state.is_open);
    CHECK(rig.state.mapped == 0);
  }
}

SCENARIO(
    "GIVEN a driver that does not offer the wanted format WHEN opening THEN the error lists what it offers") {
  Rig rig;
  rig.state.offered = {V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_YUV420};
  REQUIRE_THROWS_WITH(rig.open(smallConfig(V4l2PixelFormat::Mjpeg)),
                      Catch::Contains("format mjpeg is not offered") && Catch::Contains("NV12, YU12"));
  CHECK_FALSE(rig.state.is_open);
}

SCENARIO("GIVEN nodes that are not usable WHEN opening THEN the error says why") {
  WHEN("the node does not exist") {
    Rig rig;
    rig.state.open_errors = {ENOENT};
    REQUIRE_THROWS_WITH(rig.open(smallConfig()),
                        Catch::Contains("v4l2:/dev/video7: cannot open") && Catch::Contains("plugged in"));
  }
  WHEN("it is an output-only node") {
    Rig rig;
    rig.state.device_caps = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING;
    REQUIRE_THROWS_WITH(rig.open(smallConfig()), Catch::Contains("not a video capture device"));
    CHECK_FALSE(rig.state.is_open);
  }
  WHEN("it is multi-planar") {
    Rig rig;
    rig.state.device_caps = V4L2_CAP_VIDEO_CAPTURE_MPLANE | V4L2_CAP_STREAMING;
    REQUIRE_THROWS_WITH(rig.open(smallConfig()), Catch::Contains("multi-planar"));
  }
}

SCENARIO(
    "GIVEN ENODEV mid-stream and a node that is gone for a while WHEN capturing THEN it reconnects with "
    "backoff") {
  Rig rig;
  auto config = smallConfig();
  config.reconnect_initial_ms = 100;
  config.reconnect_max_ms = 400;
  rig.open(config);
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0));
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 1));
  rig.state.events.push_back(errorEvent(Kind::DqbufError, ENODEV));

  auto first = rig.source->next();
  auto second = rig.source->next();
  REQUIRE(first);
  REQUIRE(second);
  // Unplugged: the next four opens fail, the fifth succeeds; the driver restarts its sequence at 0.
  rig.state.open_errors = {ENOENT, ENOENT, ENOENT, ENOENT};
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0));
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 1));
  auto after = rig.drain();
  REQUIRE(after.size() == 2);
  THEN("the backoff doubles up to its ceiling and the numbering continues") {
    using std::chrono::milliseconds;
    CHECK(rig.sleeps == std::vector<milliseconds>{milliseconds(100), milliseconds(200), milliseconds(400),
                                                  milliseconds(400), milliseconds(400)});
    CHECK(after[0].sequence == 2);
    CHECK(after[1].sequence == 3);
    const auto status = rig.source->status();
    CHECK(status.connected);
    CHECK_FALSE(status.reconnecting);
    CHECK(status.reconnects == 1);
    CHECK(status.reconnect_attempts == 0);
    CHECK(status.dropped == 0);
    CHECK(rig.state.opens == 2);
    CHECK(rig.state.streamons == 2);
  }
}

SCENARIO(
    "GIVEN the default backoff and a camera away for 20 attempts WHEN it comes back THEN no wait between "
    "attempts was over 0.5 s: a camera plugged back is reopened within 0.5 s (resume within 2 s)",
    "[reliability]") {
  Rig rig;
  auto config = smallConfig();
  const V4l2SourceConfig defaults;
  config.reconnect_initial_ms = defaults.reconnect_initial_ms;
  config.reconnect_max_ms = defaults.reconnect_max_ms;
  rig.open(config);
  rig.state.events.push_back(errorEvent(Kind::DqbufError, ENODEV));
  rig.state.open_errors = std::deque<int>(20, ENOENT);
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0));
  const auto after = rig.drain();
  REQUIRE(after.size() == 1);
  REQUIRE(rig.sleeps.size() == 21);
  using std::chrono::milliseconds;
  // 100, 200, 400, then the ceiling: it was 2000 ms, so a camera back just after an attempt waited 2 s.
  CHECK(rig.sleeps[2] == milliseconds(400));
  CHECK(*std::max_element(rig.sleeps.begin(), rig.sleeps.end()) == milliseconds(500));
  CHECK(rig.source->status().reconnects == 1);
}

SCENARIO("GIVEN POLLHUP WHEN capturing THEN the status shows reconnecting until the camera is back") {
  Rig rig;
  rig.open(smallConfig());
  rig.state.events.push_back(errorEvent(Kind::PollHangup));
  rig.state.open_errors = {ENOENT};
  std::vector<toposlam::V4l2SourceStatus> while_waiting;
  rig.during_sleep = [&] { while_waiting.push_back(rig.source->status()); };
  // Hang-up, one failed attempt, one that succeeds; then the script is empty and the rig stops.
  REQUIRE_FALSE(rig.source->next());
  REQUIRE(while_waiting.size() == 2);
  CHECK_FALSE(while_waiting[0].connected);
  CHECK(while_waiting[0].reconnecting);
  CHECK(while_waiting[0].reconnect_attempts == 1);
  CHECK(while_waiting[0].last_error.find("POLLHUP") != std::string::npos);
  CHECK(while_waiting[1].reconnect_attempts == 2);
  CHECK(while_waiting[1].last_error.find("No such file") != std::string::npos);
  const auto status = rig.source->status();
  CHECK(status.connected);
  CHECK(status.reconnects == 1);
  CHECK(rig.source->describe().find("fake, 32x16 YUYV") != std::string::npos);
}

SCENARIO(
    "GIVEN a camera that never comes back WHEN the attempt limit is reached THEN next() throws a clear "
    "error") {
  Rig rig;
  auto config = smallConfig();
  config.reconnect_max_attempts = 3;
  rig.open(config);
  rig.state.events.push_back(errorEvent(Kind::Unplug));
  rig.state.open_errors = {ENOENT, ENOENT, ENOENT, ENOENT};
  REQUIRE_THROWS_WITH(rig.source->next(), Catch::Contains("gave up after 3 reconnect attempts") &&
                                              Catch::Contains("/dev/video7"));
  const auto status = rig.source->status();
  CHECK_FALSE(status.connected);
  CHECK(status.reconnecting);
  CHECK(status.reconnect_attempts == 3);
}

SCENARIO(
    "GIVEN a BGR24 driver WHEN a frame is taken THEN it views the driver buffer until the lease is "
    "released") {
  Rig rig;
  rig.state.offered = {V4L2_PIX_FMT_BGR24};
  rig.open(smallConfig(V4l2PixelFormat::Bgr24));
  std::vector<std::uint8_t> pixels(kWidth * kHeight * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<std::uint8_t>(i % 251);
  rig.state.events.push_back(frameEvent(pixels, 0));
  auto frame = rig.source->next();
  REQUIRE(frame);
  REQUIRE(frame->buffer_lease);
  const std::uint32_t index = 0;  // the fake hands out buffers in queue order
  CHECK(frame->image.data == rig.state.buffers[index].data());
  CHECK(frame->image.at<cv::Vec3b>(0, 1) == cv::Vec3b(3, 4, 5));
  CHECK(rig.state.queued.size() == 3);  // the driver lost one buffer to us
  AND_WHEN("the lease is released") {
    frame.reset();
    THEN("the buffer is queued again") { CHECK(rig.state.queued.size() == 4); }
  }
  AND_WHEN("the source is destroyed before the lease") {
    rig.source.reset();
    CHECK(rig.state.mapped == 1);  // the lease still maps its buffer
    CHECK(frame->image.at<cv::Vec3b>(0, 1) == cv::Vec3b(3, 4, 5));
    frame.reset();
    THEN("the last mapping goes with the lease and nothing is queued on the closed device") {
      CHECK(rig.state.mapped == 0);
      CHECK(rig.state.queued.empty());
    }
  }
}

SCENARIO(
    "GIVEN the v4l2 scheme registered WHEN a missing device is opened by URI THEN the factory reports it") {
  toposlam::registerV4l2FrameSourceScheme();
  const auto schemes = toposlam::registeredFrameSourceSchemes();
  CHECK(std::any_of(schemes.begin(), schemes.end(), [](const auto& s) { return s.first == "v4l2"; }));
  CHECK_THROWS_WITH(
      toposlam::openFrameSource("v4l2:/dev/toposlam-no-such-video99?size=320x240"),
      Catch::Contains("v4l2:/dev/toposlam-no-such-video99: cannot open") && Catch::Contains("No such file"));
  CHECK_THROWS_WITH(toposlam::openFrameSource("v4l2:/dev/video0?zoom=2"),
                    Catch::Contains("unknown query key 'zoom'") && Catch::Contains("allowed: size, fps"));
}

SCENARIO("GIVEN v4l2 URIs WHEN parsed THEN parameters are read and bad ones named") {
  const auto config = toposlam::parseV4l2Uri("v4l2:/dev/video2?size=320x240&fps=15&format=mjpeg&buffers=6");
  CHECK(config.device == "/dev/video2");
  CHECK(config.width == 320);
  CHECK(config.height == 240);
  CHECK(config.fps == 15.0);
  CHECK(config.format == V4l2PixelFormat::Mjpeg);
  CHECK(config.buffer_count == 6);
  const auto defaults = toposlam::parseV4l2Uri("v4l2:/dev/video0");
  CHECK(defaults.width == 640);
  CHECK(defaults.format == V4l2PixelFormat::Yuyv);
  CHECK(toposlam::parseV4l2Uri("v4l2:/dev/video0?format=gray").format == V4l2PixelFormat::Grey);
  CHECK(toposlam::parseV4l2Uri("v4l2:/dev/video0?fps=7.5&rate=1").fps == 7.5);  // rate: the factory's key
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?size=640"),
                    Catch::Contains("size=640") && Catch::Contains("expected WxH with each side in 16..8192"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?size=8x8"),
                    Catch::Contains("size=8x8") && Catch::Contains("16..8192"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?format=h264"),
                    Catch::Contains("format=h264 is not allowed; allowed: yuyv, mjpeg, grey, gray, bgr24, rgb24"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?fps=fast"),
                    Catch::Contains("fps=fast is not a number; expected a number in 0..1000"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?fps=2000"),
                    Catch::Contains("fps=2000 is out of range; expected a number in 0..1000"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?fps=0"),
                    Catch::Contains("fps: must be in (0, 1000]"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?buffers=1"),
                    Catch::Contains("buffers=1 is out of range; expected a whole number in 2..32"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?buffers=4.5"),
                    Catch::Contains("buffers=4.5 is not a whole number"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?zoom=2"),
                    Catch::Contains("unknown query key 'zoom' for v4l2:; allowed: size, fps, format, buffers, wait, rate"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?size=320x240&size=640x480"),
                    Catch::Contains("query key 'size' given twice"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?zoom"), Catch::Contains("key=value"));
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:video0"), Catch::Contains("expected a device path"));
  CHECK_THROWS_AS(toposlam::parseV4l2Uri("images:/tmp"), FrameSourceError);
}

SCENARIO("GIVEN an unplugged camera WHEN read with nextFor THEN every call returns within one slice, reporting reconnecting") {
  Rig rig;
  auto config = smallConfig();
  config.reconnect_initial_ms = 100;
  config.reconnect_max_ms = 400;
  rig.open(config);
  rig.state.events.push_back(errorEvent(Kind::PollHangup));
  rig.state.open_errors = {ENOENT, ENOENT};  // attempts 1 and 2 fail, attempt 3 opens the camera
  toposlam::Frame frame;
  std::vector<toposlam::FrameSourceState> states;
  toposlam::SourceWait wait = toposlam::SourceWait::Timeout;
  for (int call = 0; call < 100 && wait == toposlam::SourceWait::Timeout; ++call) {
    if (call == 10) rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0));
    wait = rig.source->nextFor(std::chrono::milliseconds(50), frame);
    states.push_back(rig.source->state());
  }
  REQUIRE(wait == toposlam::SourceWait::Frame);
  THEN("the backoff (100 + 200 + 400 ms) was waited in slices of at most 50 ms, one per call") {
    using std::chrono::milliseconds;
    CHECK(rig.sleeps.size() == 14);
    CHECK(std::all_of(rig.sleeps.begin(), rig.sleeps.end(), [](milliseconds d) { return d <= milliseconds(50); }));
    milliseconds total{0};
    for (const milliseconds d : rig.sleeps) total += d;
    CHECK(total == milliseconds(700));
    CHECK(states.front().link == toposlam::SourceLink::Reconnecting);
    CHECK(states[2].reconnect_attempts == 1);
    CHECK(states.back().link == toposlam::SourceLink::Streaming);
    CHECK(states.back().reconnects == 1);
  }
}

SCENARIO("GIVEN a reconnect backoff in progress WHEN interrupt() is called THEN nextFor ends the stream") {
  Rig rig;
  rig.open(smallConfig());
  rig.state.events.push_back(errorEvent(Kind::Unplug));
  rig.during_sleep = [&] { rig.source->interrupt(); };
  toposlam::Frame frame;
  CHECK(rig.source->nextFor(std::chrono::milliseconds(50), frame) == toposlam::SourceWait::Timeout);  // lost
  CHECK(rig.source->nextFor(std::chrono::milliseconds(50), frame) == toposlam::SourceWait::End);
  CHECK(rig.source->nextFor(std::chrono::milliseconds(50), frame) == toposlam::SourceWait::End);
  CHECK_FALSE(rig.source->next());
}

SCENARIO("GIVEN wait_at_start and no device node yet WHEN the source is made THEN it waits for the camera") {
  Rig rig;
  auto config = smallConfig();
  config.wait_at_start = true;
  rig.state.open_errors = {ENOENT, ENOENT};  // at start, then attempt 1; attempt 2 opens it
  rig.open(config);
  CHECK(rig.source->state().link == toposlam::SourceLink::Reconnecting);
  CHECK(rig.source->describe().find("(reconnecting)") != std::string::npos);
  CHECK(rig.state.opens == 0);
  rig.state.events.push_back(frameEvent(yuyv(kWidth, kHeight, 128, 128, 128), 0));
  const auto frames = rig.drain();
  REQUIRE(frames.size() == 1);
  CHECK(rig.state.opens == 1);
  CHECK(rig.source->state().link == toposlam::SourceLink::Streaming);
  CHECK(rig.source->status().reconnects == 1);
  AND_WHEN("the node exists but cannot be used (permissions)") {
    Rig denied;
    denied.state.open_errors = {EACCES};
    THEN("waiting does not hide it: the constructor fails with the hint") {
      CHECK_THROWS_WITH(denied.open(config), Catch::Contains("video' group"));
    }
  }
}

SCENARIO("GIVEN the URI key wait WHEN parsed THEN switches are accepted and anything else is refused by name") {
  CHECK(toposlam::parseV4l2Uri("v4l2:/dev/video0?wait=1").wait_at_start);
  CHECK_FALSE(toposlam::parseV4l2Uri("v4l2:/dev/video0?wait=0").wait_at_start);
  CHECK(toposlam::parseV4l2Uri("v4l2:/dev/video0?wait=yes").wait_at_start);
  CHECK_FALSE(toposlam::parseV4l2Uri("v4l2:/dev/video0?wait=off").wait_at_start);
  toposlam::V4l2SourceConfig waiting;
  waiting.wait_at_start = true;
  CHECK(toposlam::parseV4l2Uri("v4l2:/dev/video0", waiting).wait_at_start);  // the daemon's default
  CHECK_FALSE(toposlam::parseV4l2Uri("v4l2:/dev/video0?wait=0", waiting).wait_at_start);
  CHECK_THROWS_WITH(toposlam::parseV4l2Uri("v4l2:/dev/video0?wait=maybe"),
                    Catch::Contains("wait=maybe is not a switch; allowed: 1, 0, true, false"));
}
