// Image-folder/glob frame sources (file_sources.hpp).
#include "toposlam/io/file_sources.hpp"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include <spdlog/spdlog.h>

#include "toposlam/core/csv.hpp"
#include "toposlam/core/natural_order.hpp"
#include "toposlam/io/image_file.hpp"

namespace toposlam {

namespace fs = std::filesystem;

namespace {

std::string lowerExtension(const std::string& name) {
  std::string extension = fs::path(name).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return extension;
}

bool hasGlobCharacters(const std::string& text) { return text.find_first_of("*?[") != std::string::npos; }

/// Natural order by file name, then by the whole path (files of one folder sort as "2.jpg" < "10.jpg").
void sortFilesNaturally(std::vector<std::string>& files) {
  std::stable_sort(files.begin(), files.end(), [](const std::string& a, const std::string& b) {
    const std::string name_a = fs::path(a).filename().string(), name_b = fs::path(b).filename().string();
    if (name_a != name_b) return naturalLess(name_a, name_b);
    return naturalLess(a, b);
  });
}

SkipReason skipReasonOf(ImageReadError::Kind kind) {
  switch (kind) {
    case ImageReadError::Kind::Unreadable:
      return SkipReason::Unreadable;
    case ImageReadError::Kind::Truncated:
      return SkipReason::Truncated;
    case ImageReadError::Kind::TooLarge:
      return SkipReason::TooLarge;
    case ImageReadError::Kind::Corrupt:
      break;
  }
  return SkipReason::Corrupt;
}

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Bad files named one by one: the first kSkipWarningsInFull, then a summary at most every
/// kSkipSummaryPeriodS.
constexpr int kSkipWarningsInFull = 5;
constexpr double kSkipSummaryPeriodS = 10.0;

}  // namespace

bool isImageFileName(const std::string& name) {
  const std::string extension = lowerExtension(name);
  return extension == ".png" || extension == ".jpg" || extension == ".jpeg" || extension == ".bmp";
}

bool isVideoFileName(const std::string& name) {
  static const char* const kExtensions[] = {".mp4", ".avi", ".mkv", ".mov", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv"};
  const std::string extension = lowerExtension(name);
  return std::any_of(std::begin(kExtensions), std::end(kExtensions), [&](const char* e) { return extension == e; });
}

std::vector<std::string> listImageFiles(const std::string& path_or_glob) {
  std::vector<std::string> files;
  std::error_code error;
  if (fs::is_directory(path_or_glob, error)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(path_or_glob, error)) {
      if (entry.is_regular_file(error) && isImageFileName(entry.path().filename().string())) {
        files.push_back(entry.path().string());
      }
    }
    if (error) throw FrameSourceError("images: cannot list folder '" + path_or_glob + "': " + error.message());
    if (files.empty()) {
      throw FrameSourceError("images: no .png/.jpg/.jpeg/.bmp files in folder '" + path_or_glob + "'");
    }
  } else if (hasGlobCharacters(path_or_glob)) {
    glob_t matches{};
    const int result = ::glob(path_or_glob.c_str(), GLOB_NOSORT, nullptr, &matches);
    if (result == 0) {
      for (std::size_t i = 0; i < matches.gl_pathc; ++i) {
        const std::string match = matches.gl_pathv[i];
        if (fs::is_regular_file(match, error) && isImageFileName(match)) files.push_back(match);
      }
    }
    globfree(&matches);
    if (files.empty()) throw FrameSourceError("images: no image files match '" + path_or_glob + "'");
  } else if (fs::is_regular_file(path_or_glob, error)) {
    if (!isImageFileName(path_or_glob)) {
      throw FrameSourceError("images: '" + path_or_glob + "' is not a .png/.jpg/.jpeg/.bmp file");
    }
    files.push_back(path_or_glob);
  } else {
    throw FrameSourceError("images: '" + path_or_glob + "' is neither a folder, an image file nor a matching glob");
  }
  sortFilesNaturally(files);
  return files;
}

ImageFilesSource::ImageFilesSource(const std::string& path_or_glob, double timestamp_rate_hz,
                                   std::int64_t max_pixels, bool rate_given)
    : origin_(path_or_glob),
      files_(listImageFiles(path_or_glob)),
      rate_hz_(timestamp_rate_hz),
      max_pixels_(max_pixels),
      rate_given_(rate_given),
      skip_warnings_(
          "images: skipping bad files", kSkipWarningsInFull, kSkipSummaryPeriodS,
          [](const std::string& line) { spdlog::warn("{}", line); }, steadySeconds) {
  if (!(rate_hz_ > 0)) throw FrameSourceError("images: rate must be > 0 Hz");
  if (max_pixels_ < 1) throw FrameSourceError("images: max_pixels must be >= 1");
  // The frames' own capture times, when a timestamps.csv (name,time_s) lies beside them (`toposlam sim`
  // writes one): the segmentation window is in seconds. An explicit ?fps= wins.
  if (!rate_given_ && !files_.empty()) {
    const fs::path table = fs::path(files_.front()).parent_path() / "timestamps.csv";
    std::ifstream in(table);
    CsvReader reader(in);
    CsvRecord record;
    if (in && reader.next(record)) {  // the header
      std::map<std::string, double> time_of;
      while (reader.next(record)) {
        const std::vector<std::string>& fields = record.fields;
        char* end = nullptr;
        const double t = fields.size() == 2 ? std::strtod(fields[1].c_str(), &end) : 0.0;
        if (!record.problem.empty() || fields.size() != 2 || end == fields[1].c_str() || !std::isfinite(t))
          throw FrameSourceError(table.string() + ":" + std::to_string(record.line) + ": expected name,time_s" +
                                 (record.problem.empty() ? std::string() : " (" + record.problem + ")"));
        time_of[fields[0]] = t;
      }
      for (const std::string& file : files_) {
        const auto it = time_of.find(fs::path(file).filename().string());
        if (it == time_of.end()) {
          times_.clear();
          spdlog::warn("images: {} has no time for {}: timestamps at 1 fps instead", table.string(), file);
          break;
        }
        times_.push_back(it->second);
      }
      if (!times_.empty()) timestamps_file_ = table.string();
    }
  }
}

std::string ImageFilesSource::describe() const {
  std::ostringstream rate;
  rate << rate_hz_;
  const std::string timing = rate_given_                 ? rate.str() + " fps"
                             : !timestamps_file_.empty() ? "times from " + timestamps_file_
                                                         : "no frame rate given: timestamps at 1 fps, set ?fps=HZ";
  return "images:" + origin_ + " (" + std::to_string(files_.size()) + " frames, " + timing + ")";
}

std::string ImageFilesSource::frameName(std::int64_t sequence) const {
  if (sequence < 0 || sequence >= static_cast<std::int64_t>(files_.size())) return {};
  return fs::path(files_[static_cast<std::size_t>(sequence)]).filename().string();
}

std::optional<std::int64_t> ImageFilesSource::continueAfter(std::int64_t last_sequence, const std::string& last_name) {
  if (last_name.empty()) return std::nullopt;
  std::optional<std::int64_t> last;
  if (frameName(last_sequence) == last_name) {
    last = last_sequence;
  } else {
    // Files were added or removed before it: the same file, wherever it is now.
    for (std::int64_t i = 0; i < static_cast<std::int64_t>(files_.size()) && !last; ++i)
      if (frameName(i) == last_name) last = i;
  }
  if (!last) {
    spdlog::warn("images: {} has no file {} (the last frame the map holds, number {}): starting from its first frame",
                 origin_, last_name, last_sequence);
    return std::nullopt;
  }
  next_index_ = static_cast<std::size_t>(*last + 1);
  return static_cast<std::int64_t>(next_index_);
}

std::optional<Frame> ImageFilesSource::next() {
  while (next_index_ < files_.size() && !interrupted_.load()) {
    const std::size_t index = next_index_++;
    const std::string& file = files_[index];
    // One bad file (unreadable, truncated, over the pixel cap, undecodable) is dropped, counted and
    // named; it never ends the stream.
    cv::Mat image;
    SkipReason reason = SkipReason::Corrupt;  // an image that decodes to nothing
    try {
      image = readImageFileChecked(file, ImageColor::Bgr, max_pixels_);
    } catch (const ImageReadError& e) {
      reason = skipReasonOf(e.kind());
      skip_warnings_.warn(std::string("images: skipping ") + e.what());
    }
    if (image.empty()) {
      ++skipped_[reason];
      continue;
    }
    Frame frame;
    frame.image = image;
    frame.sequence = static_cast<std::int64_t>(index);
    frame.timestamp_s = times_.empty() ? static_cast<double>(index) / rate_hz_ : times_[index];
    frame.name = fs::path(file).filename().string();
    return frame;
  }
  skip_warnings_.flush();  // the files ran out (or a stop): the count of what was not named
  return std::nullopt;
}

}  // namespace toposlam
