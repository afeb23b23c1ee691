// Private to toposlam_topology: little-endian primitives for the map file payload, with bounds-checked
// reading (a truncated or malformed payload throws std::runtime_error naming what was being read).
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace toposlam::topology_detail {

class BinaryWriter {
 public:
  /// Appends to `start` (moved in, not copied; take() hands it back).
  explicit BinaryWriter(std::string start = {}) : out_(std::move(start)) {}
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void bytes(std::string_view text) {
    u64(text.size());
    out_.append(text);
  }
  /// bytes() of what `fill(std::string&)` appends to the buffer: the size is written in after (no copy).
  template <typename Fill>
  void bytesFrom(Fill&& fill) {
    const std::size_t at = out_.size();
    u64(0);
    fill(out_);
    patchU64(at, out_.size() - at - 8);
  }
  /// Overwrites the 8 bytes at `at` (written before) with `v`.
  void patchU64(std::size_t at, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out_[at + static_cast<std::size_t>(i)] = static_cast<char>(v >> (8 * i));
  }
  void reserve(std::size_t bytes) { out_.reserve(bytes); }
  const std::string& data() const { return out_; }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

class BinaryReader {
 public:
  explicit BinaryReader(std::string_view data) : data_(data) {}
  std::uint8_t u8(const char* what) {
    need(1, what);
    return static_cast<std::uint8_t>(data_[pos_++]);
  }
  std::uint32_t u32(const char* what) {
    need(4, what);
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
      v |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(data_[pos_++])) << (8 * i);
    return v;
  }
  std::uint64_t u64(const char* what) {
    need(8, what);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i)
      v |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(data_[pos_++])) << (8 * i);
    return v;
  }
  /// A flag stored as one byte, 0 or 1; anything else is damage, refused rather than read as "true".
  bool flag(const char* what) {
    const std::uint8_t v = u8(what);
    if (v > 1) throw std::runtime_error(std::string("map data has a damaged flag in ") + what);
    return v == 1;
  }
  std::int32_t i32(const char* what) { return static_cast<std::int32_t>(u32(what)); }
  std::int64_t i64(const char* what) { return static_cast<std::int64_t>(u64(what)); }
  double f64(const char* what) { return std::bit_cast<double>(u64(what)); }
  std::string_view bytes(const char* what) {
    const std::uint64_t size = u64(what);
    if (size > data_.size() - pos_) throw std::runtime_error(std::string("map data truncated in ") + what);
    std::string_view view = data_.substr(pos_, static_cast<std::size_t>(size));
    pos_ += static_cast<std::size_t>(size);
    return view;
  }
  bool atEnd() const { return pos_ == data_.size(); }
  std::size_t remaining() const { return data_.size() - pos_; }

 private:
  void need(std::size_t n, const char* what) const {
    if (data_.size() - pos_ < n) throw std::runtime_error(std::string("map data truncated in ") + what);
  }
  std::string_view data_;
  std::size_t pos_ = 0;
};

}  // namespace toposlam::topology_detail
