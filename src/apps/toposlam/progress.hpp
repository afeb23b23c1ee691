// One progress style for the long commands (map, segment, recognition, localize, sim, capture): a single line
// on stderr, rewritten in place at most 4 times a second, with the count, the rate and the time left,
//
//   map: 812/1618 frames  50%  403.2 frames/s  ETA 2s
//
// ("map: 812 frames  403.2 frames/s" when the total is not known), and at the end one summary line,
// "map: 1618 frames in 4.0 s (403.2 frames/s)". Only on a terminal: when stderr is a pipe or a file (CI, the
// journal, a script) nothing is written, so logs hold only the commands' own lines; --quiet turns it off too.
// TOPOSLAM_PROGRESS=1 forces it on (tests), =0 off.
//
// Not thread-safe: one thread updates it.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace toposlam::cli {

class Progress {
 public:
  /// `total` < 0: unknown. `quiet`: never print.
  Progress(std::string command, std::string unit, std::int64_t total, bool quiet = false);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// `done` items so far; prints when a quarter second has passed since the last line (or at the total).
  void update(std::int64_t done);
  /// Wipes the progress line, so another stderr line (a log line) starts at column 0; the next update()
  /// draws it again.
  void clearLine();
  /// The summary line (once; the destructor calls it too).
  void finish();
  bool shown() const { return enabled_; }

  /// The progress line for `done` of `total` after `seconds` (pure; the format above).
  static std::string line(const std::string& command, const std::string& unit, std::int64_t done, std::int64_t total,
                          double seconds);
  /// The summary line.
  static std::string summary(const std::string& command, const std::string& unit, std::int64_t done, double seconds);

 private:
  double elapsed() const;
  std::string command_, unit_;
  std::int64_t total_;
  bool enabled_;
  bool drawn_ = false;
  bool finished_ = false;
  std::int64_t done_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace toposlam::cli
