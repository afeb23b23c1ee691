// FrameRecorder: frames + timestamps.csv into a folder; see the header.
#include "toposlam/io/frame_recorder.hpp"

#include <cstdio>
#include <cerrno>
#include <cstring>

#include "toposlam/io/file_sources.hpp"
#include "toposlam/io/image_codec.hpp"

namespace toposlam {

namespace fs = std::filesystem;

FrameRecorder::FrameRecorder(fs::path folder, FrameRecorderConfig config)
    : folder_(std::move(folder)), config_(std::move(config)) {
  if (config_.format != "jpg" && config_.format != "png")
    throw FrameSourceError("record: format '" + config_.format + "' is not jpg or png");
  if (config_.jpeg_quality < 1 || config_.jpeg_quality > 100)
    throw FrameSourceError("record: JPEG quality " + std::to_string(config_.jpeg_quality) + " is outside 1 .. 100");
  std::error_code error;
  fs::create_directories(folder_, error);
  if (error) throw FrameSourceError("record: cannot create the folder " + folder_.string() + ": " + error.message());
  for (const fs::directory_entry& entry : fs::directory_iterator(folder_, error)) {
    const std::string name = entry.path().filename().string();
    if (name == "timestamps.csv" || isImageFileName(name))
      throw FrameSourceError("record: " + folder_.string() + " already holds a recording (" + name +
                             "); give an empty or new folder");
  }
  if (error) throw FrameSourceError("record: cannot list " + folder_.string() + ": " + error.message());
  const fs::path table = folder_ / "timestamps.csv";
  timestamps_.open(table);
  if (!timestamps_) throw FrameSourceError("record: cannot write " + table.string() + ": " + std::strerror(errno));
  timestamps_ << "name,time_s\n";
}

bool FrameRecorder::record(const Frame& frame) {
  if (full_ || frame.image.empty()) return false;
  try {
    encodeImage(frame.image, config_.format == "jpg" ? ImageFormat::Jpeg : ImageFormat::Png, encoded_,
                config_.jpeg_quality);
  } catch (const ImageCodecError& e) {
    throw FrameSourceError("record: cannot encode frame " + std::to_string(frame.sequence) + " as " + config_.format +
                           ": " + e.what());
  }
  if (bytes_ + encoded_.size() > config_.max_bytes) {
    full_ = true;
    return false;
  }
  char name[32];
  std::snprintf(name, sizeof name, "%06lld.%s", static_cast<long long>(frames_), config_.format.c_str());
  const fs::path path = folder_ / name;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw FrameSourceError("record: cannot write " + path.string() + ": " + std::strerror(errno));
  const std::size_t written = std::fwrite(encoded_.data(), 1, encoded_.size(), file);
  const int write_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (written != encoded_.size() || !closed) {
    std::error_code ignored;
    fs::remove(path, ignored);  // no truncated frame in a recording
    throw FrameSourceError("record: write failed: " + path.string() + ": " +
                           std::strerror(written != encoded_.size() ? write_errno : errno));
  }
  char line[64];
  std::snprintf(line, sizeof line, "%s,%.6f\n", name, frame.timestamp_s);
  timestamps_ << line << std::flush;
  if (!timestamps_) throw FrameSourceError("record: write failed: " + (folder_ / "timestamps.csv").string());
  bytes_ += encoded_.size();
  ++frames_;
  return true;
}

void FrameRecorder::finish() {
  timestamps_.flush();
  if (!timestamps_) throw FrameSourceError("record: write failed: " + (folder_ / "timestamps.csv").string());
  timestamps_.close();
}

}  // namespace toposlam
