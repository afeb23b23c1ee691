// Every message type's round trip: what LcmPipelineSink encodes from the pipeline's records (place_t with
// its place_alternative_t, place_event_t with the JPEG thumbnail, topology_t with topology_node_t and
// topology_edge_t, status_t with stage_status_t) is written through liblcm's file:// provider, read back
// with LcmLogReader and decoded, and every field is the one given; motion_t (toposlam-bridge's) encoded
// and decoded the same way. decodeLcmMessage, which `toposlam listen` and log replays use, reads each.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/io/image_codec.hpp"
#include "toposlam/platform/lcm_log.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam_lcm/motion_t.hpp"
#include "toposlam_lcm/place_event_t.hpp"
#include "toposlam_lcm/place_t.hpp"
#include "toposlam_lcm/place_v1_t.hpp"
#include "toposlam_lcm/status_t.hpp"
#include "toposlam_lcm/status_v1_t.hpp"
#include "toposlam_lcm/status_v2_t.hpp"
#include "toposlam_lcm/status_v3_t.hpp"
#include "toposlam_lcm/topology_t.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

template <typename Message>
Message decodeAs(const LcmLogEvent& event) {
  Message m{};
  REQUIRE(m.decode(event.data.data(), 0, static_cast<int>(event.data.size())) ==
          static_cast<int>(event.data.size()));
  return m;
}

/// A 16x12 BGR thumbnail: smooth ramps, so JPEG keeps it within a few levels.
cv::Mat rampThumbnail() {
  cv::Mat t(12, 16, CV_8UC3);
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x)
      t.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<std::uint8_t>(40 + 8 * x), static_cast<std::uint8_t>(60 + 8 * y), 128);
  return t;
}

/// One frame's passage with everything set: a finished place, a new topology, an estimate with alternatives.
FrameResult fullFrameResult() {
  FrameResult r;
  r.sequence = 5'000'000'123;  // beyond 32 bits
  r.source_time_s = 1234.5;
  r.captured_at_s = 0.0;  // long ago on CLOCK_MONOTONIC: the latency is positive
  r.lambda2 = 0.375;
  r.estimate.place = 7;
  r.estimate.node = 3;
  r.estimate.probability = 0.625;
  r.estimate.is_new = false;
  r.estimate.alternatives = {{1, 0.25}, {-1, 0.125}};
  r.estimate.map_revision = 9;
  r.revisit = RevisitEstimate{4'000'000'110, 3.25, 6, 2};  // back at frame ..110 of place 6, node 2
  ClosedPlace place;
  place.place = 7;
  place.first_frame = 4'000'000'100;
  place.last_frame = 4'000'000'140;
  place.representative_frame = 4'000'000'120;
  place.keypoints = 77;
  place.thumbnail = rampThumbnail();
  r.finished_places.push_back(FinishedPlace{place, PlaceAssignment{7, 3, false, 0.625}});
  auto topology = std::make_shared<TopologySnapshot>();
  topology->map_revision = 9;
  topology->probability = 0.8125;
  topology->particles = 300;
  topology->nodes = {TopologyNode{0, {0, 2}, {10, -1}}, TopologyNode{1, {1}, {4'000'000'020}}};
  topology->edges = {TopologyEdge{0, 1, 2}, TopologyEdge{1, 0, 1}};
  r.topology = topology;
  return r;
}

PipelineStatus fullStatus() {
  PipelineStatus s;
  s.uptime_s = 61.5;
  s.fps = 29.75;
  s.frames_captured = 3'000'000'001;
  s.frames_published = 3'000'000'000;
  s.frames_dropped = 17;
  s.queue_kept_waits = 5;
  s.source_skipped = 2 + 3 + 5 + 7 + 11 + 13 + 17;
  s.source_skipped_by_reason.count = {2, 3, 5, 7, 11, 13, 17};  // unreadable, truncated, ... other
  s.source_link = SourceLink::Reconnecting;
  s.source_reconnects = 4;
  s.source_reconnect_attempts = 6;
  s.source_dropped = 8;
  s.latency = LatencyStats{3.5, 12.25, 40.5, 1000};
  s.cpu_percent = 72.5;
  s.places = 24;
  s.map_revision = 23;
  s.maps_saved = 3;
  s.state = "stopping";
  StageStatus capture;
  capture.name = "capture";
  capture.latency = LatencyStats{0.5, 1.5, 2.5, 10};
  capture.processed = 3'000'000'001;
  capture.dropped = 0;
  capture.queue_depth = 0;
  capture.queue_capacity = 0;
  capture.cpu_percent = 1.25;
  StageStatus topology;
  topology.name = "topology";
  topology.latency = LatencyStats{4.75, 5.0, 5.25, 10};
  topology.processed = 2'999'999'990;
  topology.dropped = 11;
  topology.queue_depth = 6;
  topology.queue_capacity = 8;
  topology.cpu_percent = 35.5;
  s.stages = {capture, topology};
  return s;
}

}  // namespace

TEST_CASE("GIVEN a frame result with a finished place, a new topology and an estimate, and a status WHEN the "
          "sink publishes them into an LCM log and they are decoded THEN every field comes back",
          "[platform][lcm][round-trip]") {
  const fs::path dir = fs::path(TOPOSLAM_BINARY_DIR) / "tests" / "platform";
  fs::create_directories(dir);
  const std::string path = (dir / "round-trip.lcmlog").string();
  fs::remove(path);
  const LcmChannels channels;
  MotionStatusCounters motion;
  motion.messages.store(5);
  motion.use.store(static_cast<int>(MotionUse::Used));
  motion.standing_frames.store(11);
  motion.refused.store(3);
  motion.malformed.store(4);
  motion.fragments_abandoned.store(6);
  const std::int64_t before_us = monotonicMicroseconds();
  {
    LcmPipelineSink sink("file://" + path + "?mode=w", channels, 95, &motion);
    sink.publish(fullFrameResult());
    sink.publishStatus(fullStatus());
    REQUIRE(sink.failures() == 0);
  }
  const std::int64_t after_us = monotonicMicroseconds();

  LcmLogReader reader(path);
  std::vector<LcmLogEvent> events;
  for (LcmLogEvent e; reader.next(e);) events.push_back(e);
  REQUIRE(events.size() == 4);
  CHECK(events[0].channel == channels.place_event);
  CHECK(events[1].channel == channels.topology);
  CHECK(events[2].channel == channels.place);
  CHECK(events[3].channel == channels.status);

  SECTION("place_event_t: the place, its decision, its frames and its thumbnail") {
    const auto m = decodeAs<toposlam_lcm::place_event_t>(events[0]);
    CHECK(m.utime >= before_us);
    CHECK(m.utime <= after_us);
    CHECK(m.place == 7);
    CHECK(m.node == 3);
    CHECK(m.is_new == false);
    CHECK(m.probability == 0.625f);
    CHECK(m.first_frame == 4'000'000'100);
    CHECK(m.last_frame == 4'000'000'140);
    CHECK(m.representative_frame == 4'000'000'120);
    CHECK(m.keypoints == 77);
    CHECK(m.thumbnail_width == 16);
    CHECK(m.thumbnail_height == 12);
    CHECK(m.map_revision == 9);
    REQUIRE(m.jpeg_size == static_cast<std::int32_t>(m.jpeg.size()));
    REQUIRE(m.jpeg_size > 0);
    const cv::Mat decoded = decodeImage(m.jpeg.data(), m.jpeg.size(), ImageColor::Bgr);
    REQUIRE(decoded.size() == cv::Size(16, 12));
    CHECK(cv::norm(decoded, rampThumbnail(), cv::NORM_INF) <= 6.0);  // JPEG at quality 95
  }
  SECTION("topology_t: nodes with their places and representatives, edges with their counts") {
    const auto m = decodeAs<toposlam_lcm::topology_t>(events[1]);
    CHECK(m.map_revision == 9);
    CHECK(m.probability == 0.8125);
    CHECK(m.particles == 300);
    CHECK(m.current_node == 3);  // the estimate's node
    REQUIRE(m.num_nodes == 2);
    CHECK(m.nodes[0].id == 0);
    CHECK(m.nodes[0].places == std::vector<std::int32_t>{0, 2});
    CHECK(m.nodes[0].representative_frames == std::vector<std::int64_t>{10, -1});
    CHECK(m.nodes[1].id == 1);
    CHECK(m.nodes[1].places == std::vector<std::int32_t>{1});
    CHECK(m.nodes[1].representative_frames == std::vector<std::int64_t>{4'000'000'020});
    REQUIRE(m.num_edges == 2);
    CHECK((m.edges[0].from_node == 0 && m.edges[0].to_node == 1 && m.edges[0].count == 2));
    CHECK((m.edges[1].from_node == 1 && m.edges[1].to_node == 0 && m.edges[1].count == 1));
  }
  SECTION("place_t: the frame, its estimate and alternatives, lambda2 and the source time") {
    const auto m = decodeAs<toposlam_lcm::place_t>(events[2]);
    CHECK(m.utime == 1'234'500'000);
    CHECK(m.publish_utime >= before_us);
    CHECK(m.publish_utime <= after_us);
    CHECK(m.frame == 5'000'000'123);
    CHECK(m.latency_ms > 0.0f);
    CHECK(m.place == 7);
    CHECK(m.node == 3);
    CHECK(m.probability == 0.625f);
    CHECK(m.is_new == false);
    CHECK(m.lambda2 == 0.375f);
    REQUIRE(m.num_alternatives == 2);
    CHECK(m.alternatives[0].node == 1);
    CHECK(m.alternatives[0].probability == 0.25f);
    CHECK(m.alternatives[1].node == -1);
    CHECK(m.alternatives[1].probability == 0.125f);
    CHECK(m.map_revision == 9);
    CHECK(m.match_frame == 4'000'000'110);
    CHECK(m.match_score == 3.25f);
    CHECK(m.match_place == 6);
    CHECK(m.match_node == 2);
  }
  SECTION("status_t: the pipeline's counters, the camera, motion and every stage") {
    const auto m = decodeAs<toposlam_lcm::status_t>(events[3]);
    CHECK(m.state == "stopping");
    CHECK(m.uptime_s == 61.5f);
    CHECK(m.fps == 29.75f);
    CHECK(m.frames_captured == 3'000'000'001);
    CHECK(m.frames_published == 3'000'000'000);
    CHECK(m.frames_dropped == 17);
    CHECK(m.queue_kept_waits == 5);
    CHECK(m.source_skipped == 58);
    CHECK(m.source_state == "reconnecting");
    CHECK(m.source_reconnects == 4);
    CHECK(m.source_reconnect_attempts == 6);
    CHECK(m.source_dropped == 8);
    CHECK(m.latency_median_ms == 3.5f);
    CHECK(m.latency_p99_ms == 12.25f);
    CHECK(m.latency_max_ms == 40.5f);
    CHECK(m.cpu_percent == 72.5f);
    CHECK(m.places == 24);
    CHECK(m.map_revision == 23);
    CHECK(m.maps_saved == 3);
    CHECK(m.motion_messages == 5);
    CHECK(m.motion_state == "used");
    CHECK(m.motion_standing_frames == 11);
    CHECK(m.motion_refused == 3);
    CHECK(m.motion_malformed == 4);
    CHECK(m.motion_fragments_abandoned == 6);
    CHECK(m.source_skipped_unreadable == 2);
    CHECK(m.source_skipped_truncated == 3);
    CHECK(m.source_skipped_corrupt == 5);
    CHECK(m.source_skipped_too_large == 7);
    CHECK(m.source_skipped_wrong_format == 11);
    CHECK(m.source_skipped_device_error == 13);
    CHECK(m.source_skipped_other == 17);
    REQUIRE(m.num_stages == 2);
    CHECK(m.stages[0].name == "capture");
    CHECK(m.stages[0].latency_median_ms == 0.5f);
    CHECK(m.stages[0].processed == 3'000'000'001);
    CHECK(m.stages[1].name == "topology");
    CHECK(m.stages[1].latency_median_ms == 4.75f);
    CHECK(m.stages[1].latency_p99_ms == 5.0f);
    CHECK(m.stages[1].latency_max_ms == 5.25f);
    CHECK(m.stages[1].processed == 2'999'999'990);
    CHECK(m.stages[1].dropped == 11);
    CHECK(m.stages[1].queue_depth == 6);
    CHECK(m.stages[1].queue_capacity == 8);
    CHECK(m.stages[1].cpu_percent == 35.5f);
  }
  SECTION("decodeLcmMessage (listen, log replays) reads each by its channel") {
    std::vector<ReceivedMessage> received(events.size());
    for (std::size_t i = 0; i < events.size(); ++i) {
      const std::string kind = channelKind(channels, events[i].channel);
      INFO(events[i].channel);
      const LcmLogEvent& e = events[i];
      REQUIRE(decodeLcmMessage(kind, e.channel, e.data.data(), e.data.size(), received[i]));
    }
    CHECK(received[0].kind == "place_event");
    CHECK((received[0].place == 7 && received[0].node == 3 && !received[0].is_new));
    CHECK(received[1].kind == "topology");
    CHECK(received[1].node == 3);
    CHECK(received[2].kind == "place");
    CHECK(received[2].frame == 5'000'000'123);
    CHECK((received[2].place == 7 && received[2].node == 3));
    CHECK((received[2].match_frame == 4'000'000'110 && received[2].match_node == 2));
    CHECK_THAT(received[2].summary, Catch::Contains("back at frame 4000000110 (place 6, node 2, score 3.25)"));
    CHECK_THAT(received[2].json, Catch::Contains("\"match_node\":2"));
    CHECK(received[3].kind == "status");
    CHECK_THAT(received[3].json, Catch::Contains("\"frames_captured\":3000000001"));
    CHECK_THAT(received[3].json, Catch::Contains("\"motion_refused\":3"));
    CHECK_THAT(received[3].json, Catch::Contains("\"motion_malformed\":4,\"motion_fragments_abandoned\":6"));
    CHECK_THAT(received[3].json,
               Catch::Contains("\"source_skipped\":58,\"source_skipped_unreadable\":2,"
                               "\"source_skipped_truncated\":3,\"source_skipped_corrupt\":5,"
                               "\"source_skipped_too_large\":7,\"source_skipped_wrong_format\":11,"
                               "\"source_skipped_device_error\":13,\"source_skipped_other\":17"));
    CHECK_THAT(received[3].summary,
               Catch::EndsWith(
                   "  skipped 58 frames (unreadable 2, truncated 3, corrupt 5, too large 7, wrong format 11, "
                   "device error 13, other 17)"
                   "  motion used, 11 standing frames skipped, motion refused 3, motion malformed 4, "
                   "motion fragments abandoned 6"));
  }
}

TEST_CASE("GIVEN a place message recorded before match_* existed (place_v1_t) WHEN decoded THEN it reads with no match",
          "[platform][lcm]") {
  toposlam_lcm::place_v1_t old{};
  old.frame = 41;
  old.place = 2;
  old.node = 1;
  old.num_alternatives = 1;
  old.alternatives.resize(1);
  old.alternatives[0].node = 0;
  old.map_revision = 3;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(old.getEncodedSize()));
  REQUIRE(old.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  ReceivedMessage out;
  REQUIRE(decodeLcmMessage("place", "TOPOSLAM_PLACE", bytes.data(), bytes.size(), out));
  CHECK((out.frame == 41 && out.place == 2 && out.node == 1));
  CHECK((out.match_frame == -1 && out.match_node == -1));
  CHECK_THAT(out.json, Catch::Contains("\"match_frame\":-1"));
  // Cut short, neither type reads it.
  CHECK_FALSE(decodeLcmMessage("place", "TOPOSLAM_PLACE", bytes.data(), bytes.size() - 1, out));
}

TEST_CASE("GIVEN a status message recorded before motion_refused existed (status_v1_t) WHEN decoded THEN it reads "
          "with none refused",
          "[platform][lcm]") {
  toposlam_lcm::status_v1_t old{};
  old.state = "running";
  old.frames_captured = 1234;
  old.source_state = "streaming";
  old.motion_state = "used";
  old.motion_standing_frames = 17;
  old.num_stages = 1;
  old.stages.resize(1);
  old.stages[0].name = "capture";
  old.stages[0].processed = 99;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(old.getEncodedSize()));
  REQUIRE(old.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  ReceivedMessage out;
  REQUIRE(decodeLcmMessage("status", "TOPOSLAM_STATUS", bytes.data(), bytes.size(), out));
  CHECK_THAT(out.json, Catch::Contains("\"frames_captured\":1234"));
  CHECK_THAT(out.json, Catch::Contains("\"motion_standing_frames\":17"));
  CHECK_THAT(out.json, Catch::Contains("\"motion_refused\":0"));
  CHECK_THAT(out.json, Catch::Contains("\"motion_malformed\":0"));
  CHECK_THAT(out.json, Catch::Contains("\"processed\":99"));
  // Cut short, neither type reads it.
  CHECK_FALSE(decodeLcmMessage("status", "TOPOSLAM_STATUS", bytes.data(), bytes.size() - 1, out));
}

TEST_CASE(
    "GIVEN a status message recorded before source_skipped_<reason> existed (status_v2_t) WHEN decoded THEN "
    "it reads with its motion counters and every skipped frame under other",
    "[platform][lcm]") {
  toposlam_lcm::status_v2_t old{};
  old.state = "running";
  old.frames_captured = 1234;
  old.source_skipped = 6;
  old.source_state = "streaming";
  old.motion_state = "stale";
  old.motion_standing_frames = 17;
  old.motion_refused = 8;
  old.motion_malformed = 9;
  old.num_stages = 1;
  old.stages.resize(1);
  old.stages[0].name = "capture";
  old.stages[0].processed = 99;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(old.getEncodedSize()));
  REQUIRE(old.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  ReceivedMessage out;
  REQUIRE(decodeLcmMessage("status", "TOPOSLAM_STATUS", bytes.data(), bytes.size(), out));
  CHECK_THAT(out.json, Catch::Contains("\"frames_captured\":1234"));
  CHECK_THAT(out.json, Catch::Contains("\"source_skipped\":6,\"source_skipped_unreadable\":0"));
  CHECK_THAT(out.json, Catch::Contains("\"source_skipped_other\":6"));
  CHECK_THAT(out.json, Catch::Contains("\"motion_refused\":8"));
  CHECK_THAT(out.json, Catch::Contains("\"motion_malformed\":9"));
  CHECK_THAT(out.json, Catch::Contains("\"processed\":99"));
  CHECK_THAT(out.summary, Catch::Contains("  skipped 6 frames (other 6)  motion stale"));
  // Cut short, no type reads it.
  CHECK_FALSE(decodeLcmMessage("status", "TOPOSLAM_STATUS", bytes.data(), bytes.size() - 1, out));
}

TEST_CASE(
    "GIVEN a status message recorded before motion_fragments_abandoned existed (status_v3_t) WHEN decoded THEN "
    "it reads with its skipped frames by reason and its motion counters, and no fragments abandoned",
    "[platform][lcm]") {
  toposlam_lcm::status_v3_t old{};
  old.state = "running";
  old.frames_captured = 1234;
  old.source_skipped = 5;
  old.source_skipped_truncated = 2;
  old.source_skipped_corrupt = 3;
  old.source_state = "streaming";
  old.motion_state = "used";
  old.motion_standing_frames = 17;
  old.motion_refused = 8;
  old.motion_malformed = 9;
  old.num_stages = 1;
  old.stages.resize(1);
  old.stages[0].name = "capture";
  old.stages[0].processed = 99;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(old.getEncodedSize()));
  REQUIRE(old.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  ReceivedMessage out;
  REQUIRE(decodeLcmMessage("status", "TOPOSLAM_STATUS", bytes.data(), bytes.size(), out));
  CHECK_THAT(out.json, Catch::Contains("\"frames_captured\":1234"));
  CHECK_THAT(out.json, Catch::Contains("\"source_skipped\":5,\"source_skipped_unreadable\":0,"
                                       "\"source_skipped_truncated\":2,\"source_skipped_corrupt\":3"));
  CHECK_THAT(out.json, Catch::Contains("\"source_skipped_other\":0"));
  CHECK_THAT(out.json, Catch::Contains("\"motion_refused\":8,\"motion_malformed\":9,"
                                       "\"motion_fragments_abandoned\":0"));
  CHECK_THAT(out.json, Catch::Contains("\"processed\":99"));
  CHECK_THAT(out.summary, Catch::EndsWith("  skipped 5 frames (truncated 2, corrupt 3)  motion used, 17 standing "
                                          "frames skipped, motion refused 8, motion malformed 9"));
  // Cut short, no type reads it.
  CHECK_FALSE(decodeLcmMessage("status", "TOPOSLAM_STATUS", bytes.data(), bytes.size() - 1, out));
}

TEST_CASE("GIVEN a motion_t with every field set WHEN encoded and decoded THEN every field comes back, and "
          "decodeLcmMessage derives distance, speed and turn rate from it",
          "[platform][lcm][round-trip]") {
  toposlam_lcm::motion_t m{};
  m.utime = 7'000'123'456;
  m.sequence = 4'000'000'005;
  m.forward_m = 0.3;
  m.lateral_m = -0.4;
  m.turn_rad = -0.0625;
  m.linear_velocity_mps = -0.75;
  m.angular_velocity_rps = -1.5;
  m.moving = true;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));

  toposlam_lcm::motion_t back{};
  REQUIRE(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  CHECK(back.utime == 7'000'123'456);
  CHECK(back.sequence == 4'000'000'005);
  CHECK(back.forward_m == 0.3);
  CHECK(back.lateral_m == -0.4);
  CHECK(back.turn_rad == -0.0625);
  CHECK(back.linear_velocity_mps == -0.75);
  CHECK(back.angular_velocity_rps == -1.5);
  CHECK(back.moving == true);

  ReceivedMessage received;
  REQUIRE(decodeLcmMessage("motion", "TOPOSLAM_MOTION", bytes.data(), bytes.size(), received));
  CHECK(received.motion_time_s == Approx(7000.123456).margin(1e-9));  // microseconds to seconds
  CHECK(received.motion_distance_m == Approx(0.5).margin(1e-12));  // hypot(0.3, -0.4)
  CHECK(received.motion_speed_mps == 0.75);
  CHECK(received.motion_turn_rate_rps == 1.5);
  CHECK_FALSE(decodeLcmMessage("motion", "TOPOSLAM_MOTION", bytes.data(), bytes.size() - 1, received));
}
