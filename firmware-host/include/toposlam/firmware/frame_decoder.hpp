// One incremental frame decoder design for every controller link (MAVLink 2, the toposlam wheel link).
//
// Bytes arrive in arbitrary pieces (one byte, a read() of a serial port, a UDP datagram). The decoder
// keeps at most one candidate frame in a fixed buffer: it skips to a start byte (memchr over garbage),
// asks the protocol how many bytes it needs to decide, and then accepts the frame, skips it whole
// (verified but not for us: signed, MAVLink 1, unknown type), or rejects it. A rejected candidate is not
// thrown away: the search for the next start byte resumes at its second byte, so a valid frame that
// begins inside a false candidate (garbage that happened to contain a start byte) is still found.
//
// Guarantees: no allocation (the buffer is a member array), no blocking (feed() returns when the input
// is consumed), every byte is accounted for in the counters, every reason to reject has a counter.
// Thread-safety: one decoder per thread; counters() may be copied out by that thread only.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace toposlam::firmware {

/// Every class of byte and error a decoder sees. Counts only grow.
struct DecoderCounters {
  std::uint64_t bytes_in = 0;         ///< bytes fed
  std::uint64_t bytes_skipped = 0;    ///< bytes outside any verified frame (garbage, rejected candidates)
  std::uint64_t frame_bytes = 0;      ///< bytes of verified frames (accepted or skipped whole)
  std::uint64_t frames = 0;           ///< verified frames delivered
  std::uint64_t bad_crc = 0;          ///< candidates whose checksum did not match
  std::uint64_t bad_length = 0;       ///< impossible or too short length field
  std::uint64_t bad_header = 0;       ///< unsupported protocol version or incompatibility flags
  std::uint64_t unknown_message = 0;  ///< message id/type we cannot verify or do not know
  std::uint64_t signed_skipped = 0;   ///< MAVLink 2 signed frames: CRC-valid, not trusted, skipped
  std::uint64_t mavlink1_skipped = 0; ///< MAVLink 1 frames: CRC-valid, skipped
  std::uint64_t false_starts = 0;     ///< a start byte not followed by the rest of the sync pattern

  /// Damage: rejected candidates that looked like frames of ours.
  std::uint64_t errors() const { return bad_crc + bad_length + bad_header; }
};

/// What a protocol says about the candidate frame at the start of the buffer.
enum class Verdict : std::uint8_t {
  NeedMore,   ///< give me `size` bytes in total, then ask again
  Accept,     ///< a verified frame of `size` bytes for the application
  SkipFrame,  ///< a verified frame of `size` bytes that is not for us: drop it whole
  Reject,     ///< not a frame: resynchronise from the next start byte after the first
};

struct Examination {
  Verdict verdict;
  std::size_t size;                        ///< bytes needed (NeedMore) or frame size (Accept, SkipFrame)
  std::uint64_t DecoderCounters::*counter;  ///< counter to increment, or nullptr
};

/// Protocol requirements (see MavlinkProtocol, WheelLinkProtocol):
///   static constexpr std::size_t kMaxFrame;
///   static const std::uint8_t* findStart(const std::uint8_t* begin, const std::uint8_t* end);
///   static Examination examine(const std::uint8_t* buffer, std::size_t size);  // buffer[0] is a start
///   using Frame = ...;  static Frame view(const std::uint8_t* frame, std::size_t size);
template <class Protocol>
class FrameDecoder {
 public:
  using Frame = typename Protocol::Frame;

  /// Decodes `bytes`, calling on_frame(const Frame&) for each accepted frame, in order. A Frame points
  /// into the decoder's buffer and is valid during the call only.
  template <class OnFrame>
  void feed(std::span<const std::uint8_t> bytes, OnFrame&& on_frame) {
    counters_.bytes_in += bytes.size();
    const std::uint8_t* in = bytes.data();
    const std::uint8_t* const end = in + bytes.size();
    for (;;) {
      if (size_ == 0) {
        const std::uint8_t* start = Protocol::findStart(in, end);
        counters_.bytes_skipped += static_cast<std::uint64_t>(start - in);
        if (start == end) return;
        buffer_[0] = *start;
        size_ = 1;
        in = start + 1;
      }
      const Examination e = Protocol::examine(buffer_.data(), size_);
      if (e.verdict == Verdict::NeedMore) {
        // e.size > size_ and e.size <= kMaxFrame by the protocol's contract.
        const std::size_t take = std::min(e.size - size_, static_cast<std::size_t>(end - in));
        if (take == 0) return;
        std::memcpy(buffer_.data() + size_, in, take);
        size_ += take;
        in += take;
        continue;
      }
      if (e.counter != nullptr) ++(counters_.*(e.counter));
      if (e.verdict == Verdict::Reject) {
        dropFront(1);
        continue;
      }
      counters_.frame_bytes += e.size;
      if (e.verdict == Verdict::Accept) {
        ++counters_.frames;
        on_frame(Protocol::view(buffer_.data(), e.size));
      }
      dropFront(e.size, /*skipped=*/false);
    }
  }

  /// Forgets a partial candidate (e.g. after the device was reopened); its bytes count as skipped.
  void reset() {
    counters_.bytes_skipped += size_;
    size_ = 0;
  }

  const DecoderCounters& counters() const { return counters_; }
  /// Bytes of the candidate frame held back, waiting for the rest.
  std::size_t buffered() const { return size_; }

 private:
  // Removes `n` bytes from the front, then any bytes before the next start byte in the buffer.
  void dropFront(std::size_t n, bool skipped = true) {
    if (skipped) counters_.bytes_skipped += n;
    const std::uint8_t* rest = buffer_.data() + n;
    const std::uint8_t* end = buffer_.data() + size_;
    const std::uint8_t* start = Protocol::findStart(rest, end);
    counters_.bytes_skipped += static_cast<std::uint64_t>(start - rest);
    size_ = static_cast<std::size_t>(end - start);
    if (size_ > 0) std::memmove(buffer_.data(), start, size_);
  }

  std::array<std::uint8_t, Protocol::kMaxFrame> buffer_{};
  std::size_t size_ = 0;
  DecoderCounters counters_;
};

}  // namespace toposlam::firmware
