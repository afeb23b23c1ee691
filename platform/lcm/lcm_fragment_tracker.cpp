// LcmFragmentTracker: liblcm's reassembly rule (one message per sender; another message supersedes it),
// followed on datagram headers to count the fragmented messages it abandons. See the header.
#include "toposlam/platform/lcm_fragment_tracker.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace toposlam {

namespace {

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

std::uint16_t bigEndian16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((std::uint32_t{p[0]} << 8) | std::uint32_t{p[1]});
}

/// The length of the NUL-terminated name at `p` within `bytes`, or `bytes` when it has no NUL there.
std::size_t nameLength(const std::uint8_t* p, std::size_t bytes) {
  const void* nul = std::memchr(p, 0, bytes);
  return nul == nullptr ? bytes : static_cast<std::size_t>(static_cast<const std::uint8_t*>(nul) - p);
}

}  // namespace

LcmFragmentTracker::LcmFragmentTracker(LcmFragmentTrackerConfig config) : config_(std::move(config)) {
  config_.max_senders = std::max<std::size_t>(config_.max_senders, 1);
  senders_.reserve(config_.max_senders);
}

void LcmFragmentTracker::add(std::uint64_t sender, const std::uint8_t* head, std::size_t head_bytes,
                             std::size_t datagram_bytes, double now_s) {
  const std::uint32_t magic = head_bytes >= 4 ? bigEndian32(head) : 0;
  if (magic == kShortMagic) {
    ++stats_.short_messages;
    return;
  }
  if (magic != kFragmentMagic || head_bytes < kFragmentHeaderBytes || datagram_bytes < head_bytes) {
    ++stats_.garbage;
    return;
  }
  const Header h{bigEndian32(head + 4), bigEndian32(head + 8), bigEndian32(head + 12), bigEndian16(head + 16),
                 bigEndian16(head + 18)};
  if (h.count == 0 || h.number >= h.count || h.size > kMaxMessageBytes) {
    ++stats_.garbage;
    return;
  }
  Sender& s = senderOf(sender, now_s);
  // liblcm's rule: a fragment of another message drops the one in progress.
  if (s.count == 0 || s.seqno != h.seqno || s.size != h.size) {
    if (!s.settled) abandon(s, stats_.superseded);
    begin(s, h);
  }
  s.last_s = now_s;
  if (!s.settled) fragment(s, h, head, head_bytes, datagram_bytes);
}

void LcmFragmentTracker::expire(double now_s) {
  for (Sender& s : senders_)
    if (!s.settled && now_s - s.last_s >= config_.timeout_s) abandon(s, stats_.timed_out);
}

LcmFragmentTracker::Sender& LcmFragmentTracker::senderOf(std::uint64_t key, double now_s) {
  for (Sender& s : senders_)
    if (s.key == key) return s;
  Sender fresh;  // no message yet (count 0), nothing to abandon (settled)
  fresh.key = key;
  fresh.settled = true;
  fresh.last_s = now_s;
  if (senders_.size() < config_.max_senders) return senders_.emplace_back(fresh);
  // Full: the sender heard least recently makes room; its unfinished message is lost to us.
  Sender& oldest = *std::min_element(senders_.begin(), senders_.end(),
                                     [](const Sender& a, const Sender& b) { return a.last_s < b.last_s; });
  if (!oldest.settled) abandon(oldest, stats_.evicted);
  oldest = fresh;
  return oldest;
}

void LcmFragmentTracker::begin(Sender& s, const Header& h) {
  s.seqno = h.seqno;
  s.size = h.size;
  s.count = h.count;
  s.remaining = 0;
  s.started = false;
  s.settled = false;
  s.followed = true;
}

void LcmFragmentTracker::fragment(Sender& s, const Header& h, const std::uint8_t* head,
                                  std::size_t head_bytes, std::size_t datagram_bytes) {
  std::size_t data_bytes = datagram_bytes - kFragmentHeaderBytes;
  const std::uint8_t* name = head + kFragmentHeaderBytes;
  const std::size_t name_room = head_bytes - kFragmentHeaderBytes;
  const std::size_t name_bytes = nameLength(name, name_room);
  // Fragment 0's data follows the channel name (when the name fits in what was read).
  if (h.number == 0 && name_bytes < name_room) data_bytes -= name_bytes + 1;
  if (h.count != s.count || h.offset > s.size || data_bytes > s.size - h.offset) {
    ++stats_.garbage;  // liblcm drops such a fragment; its message then never completes
    return;
  }
  if (h.number == 0 && !s.started) {
    s.started = true;
    s.remaining = s.count;
    s.followed = followedChannel(name, name_bytes, name_bytes < name_room);
  }
  if (!s.started) return;  // before fragment 0: liblcm has no buffer for it yet and drops it
  if (--s.remaining == 0) {
    ++stats_.completed;
    s.settled = true;
  }
}

bool LcmFragmentTracker::followedChannel(const std::uint8_t* name, std::size_t bytes, bool whole) const {
  if (config_.channels.empty()) return true;
  if (!whole) return false;  // a name cut short is none of ours (LCM's names are at most 63 bytes)
  const std::string_view channel(reinterpret_cast<const char*>(name), bytes);
  return std::find(config_.channels.begin(), config_.channels.end(), channel) != config_.channels.end();
}

void LcmFragmentTracker::abandon(Sender& s, std::int64_t& reason) {
  if (s.followed) {
    ++reason;
    ++stats_.abandoned;
  } else {
    ++stats_.abandoned_elsewhere;
  }
  s.settled = true;
}

}  // namespace toposlam
