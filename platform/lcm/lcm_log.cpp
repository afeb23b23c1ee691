// LCM log reader and writer; see the header for the format.
#include "toposlam/platform/lcm_log.hpp"

#include <array>
#include <cerrno>
#include <cstring>

namespace toposlam {

namespace {

std::uint64_t bigEndian(const std::uint8_t* bytes, int count) {
  std::uint64_t v = 0;
  for (int i = 0; i < count; ++i) v = (v << 8) | bytes[i];
  return v;
}

void putBigEndian(std::uint8_t* bytes, std::uint64_t v, int count) {
  for (int i = count - 1; i >= 0; --i, v >>= 8) bytes[i] = static_cast<std::uint8_t>(v & 0xFF);
}

}  // namespace

LcmLogReader::LcmLogReader(const std::string& path) : path_(path) {
  in_.open(path, std::ios::binary);
  if (!in_) throw LcmLogError(path + ": cannot open the LCM log: " + std::strerror(errno));
  in_.seekg(0, std::ios::end);
  const std::streamoff end = in_.tellg();
  in_.seekg(0, std::ios::beg);
  if (end < 0) throw LcmLogError(path + ": cannot read the LCM log (not a regular file?)");
  size_ = static_cast<std::uint64_t>(end);
}

void LcmLogReader::fail(std::uint64_t at, const std::string& problem) const {
  throw LcmLogError(path_ + ": " + problem + " (event " + std::to_string(events_) + " at byte " + std::to_string(at) +
                    " of " + std::to_string(size_) + ")");
}

bool LcmLogReader::next(LcmLogEvent& event) {
  const std::uint64_t at = offset_;
  if (at == size_) return false;
  const std::uint64_t left = size_ - at;
  if (left < kLcmLogHeaderBytes)
    fail(at, "truncated: an event header needs " + std::to_string(kLcmLogHeaderBytes) + " bytes, only " +
                 std::to_string(left) + " are left (the log was cut short)");
  std::array<std::uint8_t, kLcmLogHeaderBytes> header{};
  if (!in_.read(reinterpret_cast<char*>(header.data()), header.size())) fail(at, "read error");
  const auto sync = static_cast<std::uint32_t>(bigEndian(header.data(), 4));
  if (sync != kLcmLogSyncWord) {
    char found[16];
    std::snprintf(found, sizeof found, "0x%08X", sync);
    fail(at, std::string("no LCM sync word (0xEDA1DA01), found ") + found +
                 (at == 0 ? ": not an LCM log" : ": the log is corrupt here"));
  }
  const auto channel_bytes = static_cast<std::int32_t>(bigEndian(header.data() + 20, 4));
  const auto data_bytes = static_cast<std::int32_t>(bigEndian(header.data() + 24, 4));
  if (channel_bytes <= 0 || channel_bytes > kLcmLogMaxChannelBytes)
    fail(at, "implausible channel length " + std::to_string(channel_bytes) + " (allowed 1 .. " +
                 std::to_string(kLcmLogMaxChannelBytes) + "): the log is corrupt here");
  if (data_bytes < 0 || data_bytes > kLcmLogMaxDataBytes)
    fail(at, "implausible data length " + std::to_string(data_bytes) + ": the log is corrupt here");
  const std::uint64_t body = static_cast<std::uint64_t>(channel_bytes) + static_cast<std::uint64_t>(data_bytes);
  if (body > left - kLcmLogHeaderBytes)
    fail(at, "truncated: the event announces " + std::to_string(channel_bytes) + " bytes of channel name and " +
                 std::to_string(data_bytes) + " bytes of data but only " + std::to_string(left - kLcmLogHeaderBytes) +
                 " are left (the log was cut short)");
  event.event_number = static_cast<std::int64_t>(bigEndian(header.data() + 4, 8));
  event.utime = static_cast<std::int64_t>(bigEndian(header.data() + 12, 8));
  event.offset = at;
  event.channel.resize(static_cast<std::size_t>(channel_bytes));
  event.data.resize(static_cast<std::size_t>(data_bytes));
  if (!in_.read(event.channel.data(), channel_bytes) ||
      !in_.read(reinterpret_cast<char*>(event.data.data()), data_bytes))
    fail(at, "read error");
  offset_ = at + kLcmLogHeaderBytes + body;
  ++events_;
  return true;
}

LcmLogWriter::LcmLogWriter(const std::string& path) : path_(path) {
  out_.open(path, std::ios::binary | std::ios::trunc);
  if (!out_) throw LcmLogError(path + ": cannot create the LCM log: " + std::strerror(errno));
}

void LcmLogWriter::write(std::int64_t utime, const std::string& channel, const void* data, std::size_t size) {
  if (channel.empty() || channel.size() > static_cast<std::size_t>(kLcmLogMaxChannelBytes))
    throw LcmLogError(path_ + ": channel name of " + std::to_string(channel.size()) + " bytes (allowed 1 .. 255)");
  if (size > static_cast<std::size_t>(kLcmLogMaxDataBytes))
    throw LcmLogError(path_ + ": message of " + std::to_string(size) + " bytes is too large for the log");
  std::array<std::uint8_t, kLcmLogHeaderBytes> header{};
  putBigEndian(header.data(), kLcmLogSyncWord, 4);
  putBigEndian(header.data() + 4, static_cast<std::uint64_t>(next_event_), 8);
  putBigEndian(header.data() + 12, static_cast<std::uint64_t>(utime), 8);
  putBigEndian(header.data() + 20, channel.size(), 4);
  putBigEndian(header.data() + 24, size, 4);
  out_.write(reinterpret_cast<const char*>(header.data()), header.size());
  out_.write(channel.data(), static_cast<std::streamsize>(channel.size()));
  out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out_) throw LcmLogError(path_ + ": write failed: " + std::strerror(errno));
  ++next_event_;
}

void LcmLogWriter::close() {
  out_.flush();
  if (!out_) throw LcmLogError(path_ + ": write failed: " + std::strerror(errno));
  out_.close();
}

}  // namespace toposlam
