// LcmFragmentTracker on crafted fragment headers: what liblcm's reassembly would abandon (superseded by the
// sender's next message, silent past the timeout, its sender forgotten) is counted; complete messages,
// other channels and garbage are told apart.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/platform/lcm_fragment_tracker.hpp"

using toposlam::LcmFragmentTracker;
using toposlam::LcmFragmentTrackerConfig;

namespace {

void putBigEndian(std::vector<std::uint8_t>& out, std::uint32_t value, int bytes) {
  for (int shift = 8 * (bytes - 1); shift >= 0; shift -= 8)
    out.push_back(static_cast<std::uint8_t>(value >> shift));
}

/// A fragment datagram as LCM sends it: header, for fragment 0 the channel and its NUL, then `data_bytes`.
std::vector<std::uint8_t> fragment(std::uint32_t seqno, std::uint32_t size, std::uint32_t offset,
                                   std::uint16_t number, std::uint16_t count, std::size_t data_bytes,
                                   const std::string& channel = "MOTION",
                                   std::uint32_t magic = LcmFragmentTracker::kFragmentMagic) {
  std::vector<std::uint8_t> d;
  putBigEndian(d, magic, 4);
  putBigEndian(d, seqno, 4);
  putBigEndian(d, size, 4);
  putBigEndian(d, offset, 4);
  putBigEndian(d, number, 2);
  putBigEndian(d, count, 2);
  if (number == 0) {
    d.insert(d.end(), channel.begin(), channel.end());
    d.push_back(0);
  }
  d.resize(d.size() + data_bytes, 0xAB);
  return d;
}

/// Fragment `number` of a 3-fragment message of 3000 bytes (1000 each), as the tracker reads it.
void feed(LcmFragmentTracker& tracker, std::uint64_t sender, std::uint32_t seqno, std::uint16_t number,
          double now_s, const std::string& channel = "MOTION") {
  const std::vector<std::uint8_t> d = fragment(seqno, 3000, 1000U * number, number, 3, 1000, channel);
  tracker.add(sender, d.data(), std::min<std::size_t>(d.size(), 84), d.size(), now_s);
}

}  // namespace

TEST_CASE("GIVEN a complete 3-fragment message WHEN tracked THEN it is complete and nothing is abandoned",
          "[platform][lcm][fragments]") {
  LcmFragmentTracker tracker;
  for (std::uint16_t n = 0; n < 3; ++n) feed(tracker, 1, 10, n, 0.001 * n);
  tracker.expire(100.0);
  CHECK(tracker.stats().completed == 1);
  CHECK(tracker.stats().abandoned == 0);
  CHECK(tracker.stats().garbage == 0);
  // The next message of the same sender supersedes nothing: the first one was finished.
  for (std::uint16_t n = 0; n < 3; ++n) feed(tracker, 1, 11, n, 100.0);
  CHECK(tracker.stats().completed == 2);
  CHECK(tracker.stats().abandoned == 0);
}

TEST_CASE(
    "GIVEN a message with a fragment missing WHEN the same sender begins another THEN one is abandoned "
    "(superseded), as liblcm drops it",
    "[platform][lcm][fragments]") {
  LcmFragmentTracker tracker;
  feed(tracker, 1, 10, 0, 0.0);
  feed(tracker, 1, 10, 2, 0.0);  // fragment 1 lost
  feed(tracker, 2, 50, 0, 0.0);  // another sender's message does not supersede it
  CHECK(tracker.stats().abandoned == 0);
  for (std::uint16_t n = 0; n < 3; ++n) feed(tracker, 1, 11, n, 0.01);
  CHECK(tracker.stats().abandoned == 1);
  CHECK(tracker.stats().superseded == 1);
  CHECK(tracker.stats().completed == 1);
  // A late fragment of the abandoned message supersedes the finished one: nothing more to count, and it
  // starts nothing (no fragment 0), so it is abandoned in turn when sender 1 goes on.
  feed(tracker, 1, 10, 1, 0.02);
  feed(tracker, 1, 12, 0, 0.03);
  CHECK(tracker.stats().abandoned == 2);
}

TEST_CASE(
    "GIVEN fragments before fragment 0 WHEN the rest come THEN the message is abandoned, as liblcm cannot "
    "finish it",
    "[platform][lcm][fragments]") {
  LcmFragmentTracker tracker;
  feed(tracker, 1, 10, 1, 0.0);  // liblcm has no buffer before fragment 0: dropped
  feed(tracker, 1, 10, 0, 0.0);
  feed(tracker, 1, 10, 2, 0.0);
  CHECK(tracker.stats().completed == 0);
  tracker.expire(5.0);
  CHECK(tracker.stats().abandoned == 1);
  CHECK(tracker.stats().timed_out == 1);
}

TEST_CASE(
    "GIVEN an incomplete message WHEN its sender goes silent THEN it is abandoned once the timeout has "
    "passed, "
    "once",
    "[platform][lcm][fragments]") {
  LcmFragmentTrackerConfig config;
  config.timeout_s = 2.0;
  LcmFragmentTracker tracker(config);
  feed(tracker, 7, 1, 0, 10.0);
  feed(tracker, 7, 1, 1, 10.5);
  tracker.expire(12.4);  // 1.9 s after its last fragment
  CHECK(tracker.stats().abandoned == 0);
  tracker.expire(12.5);
  CHECK(tracker.stats().abandoned == 1);
  CHECK(tracker.stats().timed_out == 1);
  tracker.expire(20.0);
  feed(tracker, 7, 1, 2, 20.0);  // its last fragment, far too late: counted already, not again
  feed(tracker, 7, 2, 0, 20.1);
  CHECK(tracker.stats().abandoned == 1);
  CHECK(tracker.stats().completed == 0);
}

TEST_CASE(
    "GIVEN more senders than the cap, each with an incomplete message WHEN tracked THEN memory stays at the "
    "cap and every forgotten message counts as abandoned",
    "[platform][lcm][fragments]") {
  LcmFragmentTrackerConfig config;
  config.max_senders = 8;
  LcmFragmentTracker tracker(config);
  for (std::uint64_t sender = 0; sender < 100; ++sender)
    feed(tracker, sender, 1, 0, 0.001 * static_cast<double>(sender));
  CHECK(tracker.senders() == 8);
  CHECK(tracker.stats().evicted == 92);
  CHECK(tracker.stats().abandoned == 92);
  tracker.expire(10.0);  // the 8 still followed time out
  CHECK(tracker.stats().abandoned == 100);
  CHECK(tracker.stats().timed_out == 8);
  // A finished sender's room is taken without counting anything.
  for (std::uint64_t sender = 100; sender < 108; ++sender) feed(tracker, sender, 1, 0, 11.0);
  CHECK(tracker.stats().abandoned == 100);
}

TEST_CASE(
    "GIVEN followed channels WHEN messages on other channels are abandoned THEN they are counted apart, and "
    "one "
    "whose fragment 0 never came counts, its channel unknown",
    "[platform][lcm][fragments]") {
  LcmFragmentTrackerConfig config;
  config.channels = {"MOTION"};
  LcmFragmentTracker tracker(config);
  feed(tracker, 1, 1, 0, 0.0, "TOPOSLAM_PLACE_EVENT");
  feed(tracker, 1, 2, 0, 0.0, "MOTION");
  feed(tracker, 1, 3, 1, 0.0);  // headless
  feed(tracker, 1, 4, 0, 0.0, "MOTION");
  CHECK(tracker.stats().abandoned_elsewhere == 1);
  CHECK(tracker.stats().abandoned == 2);
}

TEST_CASE("GIVEN garbage datagrams WHEN tracked THEN they are counted as garbage and abandon nothing",
          "[platform][lcm][fragments]") {
  LcmFragmentTracker tracker;
  feed(tracker, 1, 10, 0, 0.0);
  auto add = [&tracker](const std::vector<std::uint8_t>& d) {
    tracker.add(1, d.data(), std::min<std::size_t>(d.size(), 84), d.size(), 0.0);
  };
  add({'x', 'y'});                                        // shorter than a magic
  add(fragment(10, 3000, 0, 1, 3, 100, "", 0x12345678));  // bad magic
  const std::vector<std::uint8_t> whole = fragment(10, 3000, 0, 1, 3, 0);
  add(std::vector<std::uint8_t>(whole.begin(), whole.begin() + 12));  // header cut short
  add(fragment(10, 3000, 1000, 3, 3, 1000));                          // fragment 3 of 3
  add(fragment(10, 3000, 1000, 0, 0, 1000));                          // 0 fragments
  add(fragment(10, 3000, 1000, 1, 4, 1000));                          // 4 fragments, of a 3-fragment message
  add(fragment(10, 3000, 2500, 2, 3, 1000));                          // data beyond the message's end
  add(fragment(10, (1u << 28) + 1, 0, 1, 3, 1000));                   // larger than LCM allows
  CHECK(tracker.stats().garbage == 8);
  CHECK(tracker.stats().abandoned == 0);
  // A short message ('LC02') is neither, and leaves the message in progress alone.
  add(fragment(11, 3000, 0, 1, 3, 10, "", LcmFragmentTracker::kShortMagic));
  CHECK(tracker.stats().short_messages == 1);
  feed(tracker, 1, 10, 1, 0.0);
  feed(tracker, 1, 10, 2, 0.0);
  CHECK(tracker.stats().completed == 1);
  CHECK(tracker.stats().abandoned == 0);
}
