// LCM log files, read and written without liblcm or a network: the format lcm-logger writes and liblcm's
// `file://PATH?mode=w` provider writes (https://lcm-proj.github.io/lcm/content/log-file-format.html). A log
// is a sequence of events, each a 28-byte big-endian header
//
//   sync word 0xEDA1DA01 (u32) | event number (i64) | receive time, microseconds since 1970 (i64)
//   | channel length (i32) | data length (i32)
//
// followed by the channel name (no terminating NUL) and the message bytes.
//
// The reader checks every header: a missing sync word, an implausible length or an event cut short is a
// LcmLogError naming the file and the byte offset of the event ("robot.lcmlog: the event at byte 1234
// announces 5000 bytes of data but only 120 are left (the log was cut short)"). Events read before the
// problem have been returned already, so a caller can keep them and report the rest.
//
// Thread-safety: one reader or writer per thread.
#pragma once

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace toposlam {

class LcmLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LcmLogEvent {
  std::int64_t event_number = 0;
  std::int64_t utime = 0;            ///< when the logger received it, microseconds since 1970 (the logger's clock)
  std::string channel;
  std::vector<std::uint8_t> data;    ///< the message as published (type hash first)
  std::uint64_t offset = 0;          ///< byte offset of the event's header in the file
};

inline constexpr std::uint32_t kLcmLogSyncWord = 0xEDA1DA01u;
inline constexpr std::size_t kLcmLogHeaderBytes = 28;
inline constexpr std::int32_t kLcmLogMaxChannelBytes = 255;          ///< longer is refused as corrupt
inline constexpr std::int32_t kLcmLogMaxDataBytes = 256 * 1024 * 1024;  ///< larger is refused as corrupt

class LcmLogReader {
 public:
  /// Opens `path`; LcmLogError naming it when it cannot.
  explicit LcmLogReader(const std::string& path);
  /// The next event; false at the end of the file (after a whole event). LcmLogError (file, offset,
  /// problem) on a corrupt or truncated event.
  bool next(LcmLogEvent& event);
  /// Byte offset of the next event.
  std::uint64_t offset() const { return offset_; }
  std::uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(std::uint64_t at, const std::string& problem) const;
  std::string path_;
  std::ifstream in_;
  std::uint64_t offset_ = 0;
  std::uint64_t size_ = 0;
  std::int64_t events_ = 0;
};

class LcmLogWriter {
 public:
  /// Creates (truncates) `path`; LcmLogError naming it when it cannot.
  explicit LcmLogWriter(const std::string& path);
  /// Appends one event, numbered from 0. LcmLogError on a bad channel or a failed write.
  void write(std::int64_t utime, const std::string& channel, const void* data, std::size_t size);
  /// Flushes; LcmLogError when a write failed.
  void close();

 private:
  std::string path_;
  std::ofstream out_;
  std::int64_t next_event_ = 0;
};

}  // namespace toposlam
