// `toposlam capture URI --count N`: reads frames from a camera (v4l2:/dev/videoN?..., libcamera:ID) and
// prints one line per frame (sequence, timestamp, size) and a summary (frames, drops, skips, reconnects,
// rate, and the age of each frame when it came out of the source: now on CLOCK_MONOTONIC minus the
// driver's buffer timestamp, i.e. driver-to-application latency, meaningful when the driver stamps
// buffers with the monotonic clock as V4L2 drivers normally do). It is how the VM test and users check that a
// camera works before running the daemon. Registering this command also registers the `v4l2:` scheme
// with openFrameSource() (`libcamera:` is the factory's own, a module loaded on first use). Other source URIs (sim:, images:, video:) are read too (their
// age_ms is 0: their timestamps are not the monotonic clock).
//
// --record DIR writes the frames and their timestamps into DIR (io/frame_recorder.hpp): "record on the
// robot, re-process on the desk" with `toposlam map images:DIR` or, at the recorded pace,
// `toposlamd --source "images:DIR?rate=recorded"`.
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "progress.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/io/frame_recorder.hpp"
#include "toposlam/io/source_factory.hpp"
#include "v4l2_frame_source.hpp"

namespace toposlam::cli {

namespace {

struct CaptureOptions {
  std::string uri;
  int count = 30;
  double timeout_s = 0.0;
  int hold = 0;
  bool quiet = false;
  bool json = false;   ///< --json: the summary as one JSON object, no per-frame lines
  std::string record;  ///< --record DIR: "" = nothing recorded
  FrameRecorderConfig record_config;
  double record_max_mb = 1024;
};

/// Calls `stop` after `seconds` unless cancelled first (destruction cancels).
class StopTimer {
 public:
  StopTimer(double seconds, std::function<void()> stop) {
    if (seconds <= 0.0) return;
    thread_ = std::thread([this, seconds, stop = std::move(stop)] {
      std::unique_lock lock(mutex_);
      if (!cv_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return cancelled_; })) stop();
    });
  }
  ~StopTimer() {
    {
      std::lock_guard lock(mutex_);
      cancelled_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  StopTimer(const StopTimer&) = delete;
  StopTimer& operator=(const StopTimer&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool cancelled_ = false;
  std::thread thread_;
};

void runCapture(const CaptureOptions& options) {
  std::unique_ptr<FrameSource> source;
  std::function<void()> request_stop;
  std::function<std::int64_t()> reconnects = [] { return std::int64_t{0}; };
  std::function<std::int64_t()> dropped = [] { return std::int64_t{0}; };
  bool from_camera = true;  // timestamps on CLOCK_MONOTONIC: the age is meaningful
  if (options.uri.rfind("v4l2:", 0) == 0) {
    auto v4l2 = std::make_unique<V4l2FrameSource>(parseV4l2Uri(options.uri));
    V4l2FrameSource* raw = v4l2.get();
    request_stop = [raw] { raw->interrupt(); };
    reconnects = [raw] { return raw->status().reconnects; };
    dropped = [raw] { return raw->droppedFrames(); };
    source = std::move(v4l2);
  } else if (options.uri.rfind("libcamera:", 0) == 0) {
    // Opened through its module (loaded here, on first use); its counters come through FrameSource.
    source = openFrameSource(options.uri);
    FrameSource* raw = source.get();
    request_stop = [raw] { raw->interrupt(); };
    dropped = [raw] { return raw->state().dropped; };
  } else {
    source = openFrameSource(options.uri);
    FrameSource* raw = source.get();
    request_stop = [raw] { raw->interrupt(); };
    from_camera = false;
  }
  if (!options.json) std::printf("source %s\n", source->describe().c_str());
  std::fflush(stdout);
  const bool per_frame_lines = !options.quiet && !options.json;
  std::optional<FrameRecorder> recorder;
  if (!options.record.empty()) {
    FrameRecorderConfig config = options.record_config;
    config.max_bytes = static_cast<std::uint64_t>(options.record_max_mb * 1024.0 * 1024.0);
    recorder.emplace(options.record, config);
  }

  StopTimer timer(options.timeout_s, request_stop);
  std::vector<Frame> held;  // simulates a slow consumer holding zero-copy buffers
  int frames = 0;
  double first_t = 0.0;
  double last_t = 0.0;
  std::int64_t seen_reconnects = 0;
  std::vector<double> ages_ms;
  const auto started = std::chrono::steady_clock::now();
  // The progress line only when the frames' own lines are off (-q, --json).
  Progress progress("capture", "frames", options.count > 0 ? options.count : -1, per_frame_lines);
  while (options.count <= 0 || frames < options.count) {
    std::optional<Frame> frame = source->next();
    if (!frame) break;
    progress.update(frames + 1);
    if (frames == 0) first_t = frame->timestamp_s;
    last_t = frame->timestamp_s;
    ++frames;
    const double age_ms =
        from_camera ? 1e3 * (std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count() -
                        frame->timestamp_s)
               : 0.0;
    if (recorder && !recorder->record(*frame)) {
      progress.clearLine();
      std::fprintf(stderr, "capture: --record-max-mb %.0f reached after %lld frames; stopping\n", options.record_max_mb,
                   static_cast<long long>(recorder->frames()));
      break;
    }
    ages_ms.push_back(age_ms);
    if (const std::int64_t now = reconnects(); now != seen_reconnects) {
      if (!options.json) std::printf("event reconnected reconnects=%lld\n", static_cast<long long>(now));
      seen_reconnects = now;
    }
    if (per_frame_lines) {
      std::printf("frame seq=%lld t=%.6f size=%dx%d zero_copy=%d age_ms=%.2f\n",
                  static_cast<long long>(frame->sequence), frame->timestamp_s, frame->image.cols,
                  frame->image.rows, frame->buffer_lease ? 1 : 0, age_ms);
      std::fflush(stdout);
    }
    if (options.hold > 0) {
      held.push_back(std::move(*frame));
      if (static_cast<int>(held.size()) > options.hold) held.erase(held.begin());
    }
  }
  held.clear();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const double span_s = last_t - first_t;
  std::sort(ages_ms.begin(), ages_ms.end());
  auto quantile = [&](double q) {
    return ages_ms.empty()
               ? 0.0
               : ages_ms[static_cast<std::size_t>(q * static_cast<double>(ages_ms.size() - 1) + 0.5)];
  };
  progress.finish();
  if (recorder) recorder->finish();
  if (options.json) {
    JsonWriter json(std::cout);
    json.beginObject()
        .field("source", source->describe())
        .field("frames", frames)
        .field("dropped", dropped())
        .field("skipped", source->skippedFrames())
        .field("reconnects", reconnects())
        .field("seconds", wall_s)
        .field("fps", frames > 1 && span_s > 0 ? (frames - 1) / span_s : 0.0)
        .field("age_ms_median", quantile(0.5))
        .field("age_ms_p99", quantile(0.99));
    if (recorder)
      json.key("recorded").beginObject().field("folder", options.record).field("frames", recorder->frames())
          .field("bytes", static_cast<std::int64_t>(recorder->bytes())).field("full", recorder->full()).endObject();
    json.endObject();
    std::cout << "\n" << std::flush;
  } else {
    std::printf(
        "summary frames=%d dropped=%lld skipped=%lld reconnects=%lld seconds=%.3f fps=%.2f "
        "age_ms_median=%.2f age_ms_p99=%.2f\n",
        frames, static_cast<long long>(dropped()), static_cast<long long>(source->skippedFrames()),
        static_cast<long long>(reconnects()), wall_s, frames > 1 && span_s > 0 ? (frames - 1) / span_s : 0.0,
        quantile(0.5), quantile(0.99));
    std::fflush(stdout);
  }
  if (recorder) {
    if (!options.json)
      std::printf("recorded %lld frames (%.1f MB) into %s; play back: images:%s?rate=recorded\n",
                  static_cast<long long>(recorder->frames()), static_cast<double>(recorder->bytes()) / (1024.0 * 1024.0),
                  options.record.c_str(), options.record.c_str());
    std::fflush(stdout);
    if (recorder->full()) return;  // the size bound ended the capture, as asked
  }
  if (options.count > 0 && frames < options.count)
    throw std::runtime_error("capture: only " + std::to_string(frames) + " of " +
                             std::to_string(options.count) + " frames within " +
                             std::to_string(options.timeout_s) + " s");
}

}  // namespace

void addCaptureCommand(CLI::App& app) {
  // Cameras become openable by URI (openFrameSource) for every other command too.
  registerV4l2FrameSourceScheme();
  auto options = std::make_shared<CaptureOptions>();
  CLI::App* command = app.add_subcommand("capture",
                                         "Read frames from a camera and print their sequence numbers "
                                         "and timestamps (checks a camera before running the daemon); "
                                         "--record DIR keeps them for replay");
  command
      ->add_option("uri", options->uri,
                   "camera: v4l2:/dev/video0?size=640x480&fps=30&format=yuyv|mjpeg|grey|"
                   "bgr24|rgb24 or libcamera:ID (or any source URI: sim:, images:, video:)")
      ->required();
  command->add_option("--count,-n", options->count, "frames to read; 0 = until --timeout")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--timeout", options->timeout_s,
                   "stop after this many seconds (0 = never); fewer frames than "
                   "--count is then an error")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--hold", options->hold,
                   "keep the last N frames alive (a slow consumer of zero-copy buffers)")
      ->check(CLI::Range(0, 64));
  command->add_flag("--quiet,-q", options->quiet, "print the summary only");
  command->add_flag("--json", options->json, "print the summary as one JSON object (no per-frame lines)");
  command->add_option("--record", options->record,
                      "write the frames and timestamps.csv into this new or empty folder; replay with "
                      "images:DIR?rate=recorded");
  command->add_option("--record-format", options->record_config.format, "jpg or png")
      ->check(CLI::IsMember({"jpg", "png"}))
      ->needs("--record")
      ->capture_default_str();
  command->add_option("--record-quality", options->record_config.jpeg_quality, "JPEG quality of --record")
      ->check(CLI::Range(1, 100))
      ->needs("--record")
      ->capture_default_str();
  command->add_option("--record-max-mb", options->record_max_mb, "stop recording (and capturing) at this size")
      ->check(CLI::Range(0.001, 1e7))
      ->needs("--record")
      ->capture_default_str();
  command->callback([options] { runCapture(*options); });
}

}  // namespace toposlam::cli
