// LcmSubscriber's count of abandoned fragmented messages over real multicast on loopback: crafted fragment
// datagrams go to the group from one socket, some with a fragment left out, and liblcm (which delivers the
// complete ones) and the listener beside it (which counts the rest) both receive them. Exits 77 (skipped)
// when LCM cannot open the URL or multicast does not loop back here.
#include <catch2/catch.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "platform/lcm/lcm_fragment_sender.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam_lcm/motion_t.hpp"

using namespace toposlam;
using toposlam::test::lcmFragments;
using toposlam::test::MulticastSender;

namespace {

// A port no other test uses, TTL 0: the datagrams stay on this host (in_netns.sh: in a namespace of its own).
const std::string kUrl = "udpm://239.255.76.67:7683?ttl=0";

std::vector<std::uint8_t> encodedMotion(std::int64_t sequence) {
  toposlam_lcm::motion_t m{};
  m.utime = monotonicMicroseconds();
  m.sequence = sequence;
  m.forward_m = 0.25;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// Sends fragments `numbers` of message `seqno` (a motion_t on `channel`, as 3 fragments).
void sendFragments(const MulticastSender& sender, std::uint32_t seqno, const std::vector<int>& numbers,
                   const std::string& channel = LcmChannels{}.motion) {
  const auto datagrams = lcmFragments(channel, encodedMotion(seqno), seqno, 3);
  for (int n : numbers) REQUIRE(sender.send(datagrams[static_cast<std::size_t>(n)]));
}

/// Handles until `done` or 5 s have passed; true when done.
bool handleUntil(LcmSubscriber& subscriber, const std::function<bool()>& done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!done() && std::chrono::steady_clock::now() < end) subscriber.handle(50);
  return done();
}

std::unique_ptr<LcmSubscriber> subscribeOrSkip(std::vector<ReceivedMessage>& heard) {
  try {
    const LcmChannels channels;
    return std::make_unique<LcmSubscriber>(kUrl, channels, std::vector<std::string>{channels.motion},
                                           [&heard](const ReceivedMessage& m) { heard.push_back(m); });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skipped: %s\n", e.what());
    std::_Exit(77);
  }
}

}  // namespace

TEST_CASE(
    "GIVEN a subscriber on udpm:// WHEN a sender's fragmented messages lose a fragment THEN liblcm delivers "
    "the complete ones and the subscriber counts each incomplete one as abandoned",
    "[platform][lcm][fragments][multicast]") {
  std::vector<ReceivedMessage> heard;
  const auto subscriber = subscribeOrSkip(heard);
  const MulticastSender sender(kUrl);
  // A complete message first: when it does not arrive, this host does not loop multicast back.
  sendFragments(sender, 1, {0, 1, 2});
  if (!handleUntil(*subscriber, [&] { return !heard.empty(); })) {
    std::fprintf(stderr,
                 "skipped: multicast on %s does not loop back here (lo multicast, route 224.0.0.0/4)\n",
                 kUrl.c_str());
    std::_Exit(77);
  }
  REQUIRE(handleUntil(*subscriber, [&] { return subscriber->fragmentStats().completed == 1; }));
  CHECK(subscriber->fragments_abandoned() == 0);

  // Message 2 loses fragment 1; message 3 from the same sender supersedes it (liblcm drops it silently).
  sendFragments(sender, 2, {0, 2});
  sendFragments(sender, 3, {0, 1, 2});
  // Message 4 never gets past fragment 0; message 5 supersedes it.
  sendFragments(sender, 4, {0});
  sendFragments(sender, 5, {0, 1, 2});
  // On a channel this subscriber does not follow: abandoned too, but not its business.
  sendFragments(sender, 6, {0, 1}, "SOMEONE_ELSES_CHANNEL");
  sendFragments(sender, 7, {0, 1, 2});
  // Not an LCM datagram at all.
  REQUIRE(sender.send({'h', 'e', 'l', 'l', 'o'}));
  REQUIRE(handleUntil(*subscriber,
                      [&] { return heard.size() == 4 && subscriber->fragmentStats().garbage == 1; }));

  const LcmFragmentStats stats = subscriber->fragmentStats();
  CHECK(heard.size() == 4);  // messages 1, 3, 5 and 7, delivered by liblcm
  CHECK(subscriber->malformed() == 0);
  CHECK(stats.completed == 4);
  CHECK(subscriber->fragments_abandoned() == 2);
  CHECK(stats.superseded == 2);
  CHECK(stats.abandoned_elsewhere == 1);
  CHECK(stats.garbage == 1);
}

TEST_CASE("GIVEN a subscriber on memq:// WHEN asked THEN no fragments are counted (0), as none can be lost",
          "[platform][lcm][fragments]") {
  const LcmChannels channels;
  LcmSubscriber subscriber("memq://", channels, {channels.motion}, nullptr);
  subscriber.handle(0);
  CHECK(subscriber.fragments_abandoned() == 0);
  CHECK(subscriber.fragmentStats().completed == 0);
}
