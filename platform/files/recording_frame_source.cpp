// RecordingFrameSource: frames pass through, copies go to a writer thread; see the header.
#include "toposlam/io/recording_frame_source.hpp"

#include <ctime>
#include <system_error>

#include <spdlog/spdlog.h>

namespace toposlam {

namespace fs = std::filesystem;

const char* toString(RecordingState state) {
  switch (state) {
    case RecordingState::Recording: return "recording";
    case RecordingState::Full: return "full";
    case RecordingState::Failed: return "failed";
    case RecordingState::Finished: return "finished";
  }
  return "?";
}

fs::path newRecordingFolder(const fs::path& parent, std::int64_t unix_seconds) {
  const auto t = static_cast<std::time_t>(unix_seconds);
  std::tm utc{};
  gmtime_r(&t, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  fs::path folder = parent / stamp;
  std::error_code error;
  for (int n = 2; fs::exists(folder, error); ++n) folder = parent / (std::string(stamp) + "-" + std::to_string(n));
  return folder;
}

std::uint64_t bytesUnder(const fs::path& folder) {
  std::error_code error;
  std::uint64_t total = 0;
  if (!fs::is_directory(folder, error)) return 0;
  for (fs::recursive_directory_iterator it(folder, fs::directory_options::skip_permission_denied, error), end;
       !error && it != end; it.increment(error)) {
    std::error_code size_error;
    if (it->is_regular_file(size_error)) {
      const std::uintmax_t size = it->file_size(size_error);
      if (!size_error) total += size;
    }
  }
  return total;
}

RecordingFrameSource::RecordingFrameSource(std::unique_ptr<FrameSource> inner, std::unique_ptr<FrameRecorder> recorder,
                                           int queue_frames)
    : inner_(std::move(inner)),
      recorder_(std::move(recorder)),
      queue_(static_cast<std::size_t>(queue_frames < 1 ? 1 : queue_frames)),
      folder_(recorder_->folder().string()) {}

RecordingFrameSource::~RecordingFrameSource() { closeWriter(); }

std::string RecordingFrameSource::describe() const { return inner_->describe() + ", recorded into " + folder_; }

std::optional<Frame> RecordingFrameSource::next() {
  std::optional<Frame> frame = inner_->next();
  if (frame) offer(*frame);
  return frame;
}

SourceWait RecordingFrameSource::nextFor(std::chrono::milliseconds timeout, Frame& out) {
  const SourceWait result = inner_->nextFor(timeout, out);
  if (result == SourceWait::Frame) offer(out);
  return result;
}

void RecordingFrameSource::offer(const Frame& frame) {
  if (state_.load() != static_cast<int>(RecordingState::Recording) || frame.image.empty()) return;
  offered_.fetch_add(1);
  QueuedFrame item;
  item.image = takeSpare();
  frame.image.copyTo(item.image);  // reallocates only when the size changed; the driver buffer goes back as usual
  item.sequence = frame.sequence;
  item.timestamp_s = frame.timestamp_s;
  queue_.push(std::move(item));    // never waits: when the writer is behind the oldest queued copy is dropped
}

cv::Mat RecordingFrameSource::takeSpare() {
  std::lock_guard lock(mutex_);
  if (spare_.empty()) return {};
  cv::Mat image = std::move(spare_.back());
  spare_.pop_back();
  return image;
}

void RecordingFrameSource::giveBack(cv::Mat image) {
  std::lock_guard lock(mutex_);
  if (spare_.size() < queue_.capacity() + 1) spare_.push_back(std::move(image));
}

void RecordingFrameSource::stopRecording(RecordingState state, const std::string& problem) {
  {
    std::lock_guard lock(mutex_);
    problem_ = problem;
  }
  state_.store(static_cast<int>(state));
  queue_.close();
}

void RecordingFrameSource::runWriter() {
  for (std::optional<QueuedFrame> item; (item = queue_.pop());) {
    if (state_.load() != static_cast<int>(RecordingState::Recording)) continue;  // stopped: drain
    Frame frame;
    frame.image = item->image;
    frame.sequence = item->sequence;
    frame.timestamp_s = item->timestamp_s;
    try {
      if (!recorder_->record(frame)) {
        const std::string problem = "the size bound was reached";
        spdlog::warn("recording stopped: the size bound (record.max_mb) was reached after {} frames ({:.1f} MB) in "
                     "{}; the recording plays back as it is, the pipeline goes on",
                     recorder_->frames(), static_cast<double>(recorder_->bytes()) / (1024.0 * 1024.0), folder_);
        stopRecording(RecordingState::Full, problem);
      }
    } catch (const std::exception& e) {
      spdlog::error("recording stopped: {}; {} frames kept in {} (they play back), the pipeline goes on without "
                    "recording", e.what(), recorder_->frames(), folder_);
      stopRecording(RecordingState::Failed, e.what());
    }
    written_.store(recorder_->frames());
    bytes_.store(recorder_->bytes());
    frame.image.release();
    giveBack(std::move(item->image));
  }
  try {
    recorder_->finish();
  } catch (const std::exception& e) {
    if (state_.load() == static_cast<int>(RecordingState::Recording)) {
      spdlog::error("recording: {}", e.what());
      stopRecording(RecordingState::Failed, e.what());
    }
  }
  int recording = static_cast<int>(RecordingState::Recording);
  state_.compare_exchange_strong(recording, static_cast<int>(RecordingState::Finished));
}

void RecordingFrameSource::closeWriter() { queue_.close(); }

RecordingStatus RecordingFrameSource::status() const {
  RecordingStatus s;
  s.state = static_cast<RecordingState>(state_.load());
  s.offered = offered_.load();
  s.written = written_.load();
  s.dropped = queue_.counters().dropped;
  s.bytes = bytes_.load();
  s.folder = folder_;
  std::lock_guard lock(mutex_);
  s.problem = problem_;
  return s;
}

}  // namespace toposlam
