// Which fragmented LCM messages a receiver abandons, from the headers of the datagrams alone.
//
// LCM's UDP multicast transport sends a message larger than one datagram as fragments, each with a 20-byte
// header (big-endian: uint32 magic 'LC03', uint32 msg_seqno, uint32 msg_size, uint32 fragment_offset,
// uint16 fragment_no, uint16 fragments_in_msg); fragment 0 carries the channel name (NUL-terminated) before
// its data. liblcm keeps one unfinished message per sender (address:port) and throws it away, saying nothing,
// when a fragment of another message (another msg_seqno or msg_size) comes from that sender. This class
// follows the same rule on the same datagrams, so it counts what liblcm drops silently:
//   - superseded: a message still incomplete when another one from its sender begins;
//   - timed out:  a message still incomplete `timeout_s` after its last fragment (liblcm would hold it until
//                 superseded; by then nothing more of it comes: fragments are sent back to back);
//   - evicted:    an incomplete message whose sender was forgotten to make room (`max_senders`).
// As in liblcm, reassembly starts at fragment 0 (fragments before it are lost) and counts fragments, not
// which ones came. A message whose fragment 0 names a channel outside `channels` is not counted when it is
// abandoned (abandoned_elsewhere); one whose fragment 0 never came is, as its channel is unknown.
// Datagrams that cannot be fragments of a message (bad magic, a fragment number not below the count, a count
// that changes within a message, data beyond the message's size) are counted as garbage; short messages
// ('LC02') are counted and otherwise ignored, as they are by liblcm's reassembly.
//
// Pure: no I/O and no clock (times are passed in, in seconds); memory fixed at construction (max_senders).
// Thread-safety: none; one owner.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace toposlam {

struct LcmFragmentTrackerConfig {
  std::size_t max_senders = 64;       ///< senders followed at once; the least recently heard is forgotten
  double timeout_s = 2.0;             ///< an incomplete message with no fragment for this long is abandoned
  std::vector<std::string> channels;  ///< channels whose abandoned messages count; empty: every channel
};

struct LcmFragmentStats {
  std::int64_t completed = 0;  ///< fragmented messages whose every fragment came
  std::int64_t abandoned = 0;  ///< superseded + timed_out + evicted (on the channels followed)
  std::int64_t superseded = 0;
  std::int64_t timed_out = 0;
  std::int64_t evicted = 0;
  std::int64_t abandoned_elsewhere = 0;  ///< abandoned, on a channel not followed (not in `abandoned`)
  std::int64_t garbage = 0;              ///< datagrams that are no LCM packet or an inconsistent fragment
  std::int64_t short_messages = 0;       ///< 'LC02' datagrams (whole messages; not tracked)
};

class LcmFragmentTracker {
 public:
  static constexpr std::uint32_t kShortMagic = 0x4c433032;     ///< 'LC02'
  static constexpr std::uint32_t kFragmentMagic = 0x4c433033;  ///< 'LC03'
  static constexpr std::size_t kFragmentHeaderBytes = 20;
  static constexpr std::uint32_t kMaxMessageBytes = 1u << 28;  ///< liblcm's largest message

  explicit LcmFragmentTracker(LcmFragmentTrackerConfig config = {});

  /// One datagram from `sender` (any 64-bit key, e.g. IPv4 address << 16 | port) received at `now_s`:
  /// `head` is its first bytes (the header, and for fragment 0 the channel name if it fits; a name cut short
  /// counts as another channel); `datagram_bytes` its full size (MSG_TRUNC).
  void add(std::uint64_t sender, const std::uint8_t* head, std::size_t head_bytes, std::size_t datagram_bytes,
           double now_s);
  /// Abandons the incomplete messages with no fragment since now_s - timeout_s.
  void expire(double now_s);
  const LcmFragmentStats& stats() const { return stats_; }
  std::size_t senders() const { return senders_.size(); }

 private:
  struct Header {
    std::uint32_t seqno, size, offset;
    std::uint16_t number, count;
  };
  /// The message a sender is sending now.
  struct Sender {
    std::uint64_t key = 0;
    std::uint32_t seqno = 0, size = 0;
    std::uint16_t count = 0;      ///< fragments_in_msg
    std::uint32_t remaining = 0;  ///< fragments still to come, once fragment 0 came
    bool started = false;         ///< fragment 0 came (liblcm reassembles from there)
    bool settled = false;         ///< complete, or counted as abandoned: nothing more to count
    bool followed = true;         ///< on a channel in config.channels (true while unknown)
    double last_s = 0.0;          ///< when its last fragment came
  };

  Sender& senderOf(std::uint64_t key, double now_s);
  void begin(Sender& s, const Header& h);
  void fragment(Sender& s, const Header& h, const std::uint8_t* head, std::size_t head_bytes,
                std::size_t datagram_bytes);
  bool followedChannel(const std::uint8_t* name, std::size_t bytes, bool whole) const;
  void abandon(Sender& s, std::int64_t& reason);

  LcmFragmentTrackerConfig config_;
  std::vector<Sender> senders_;  ///< reserved to max_senders; searched linearly (a few dozen)
  LcmFragmentStats stats_;
};

}  // namespace toposlam
