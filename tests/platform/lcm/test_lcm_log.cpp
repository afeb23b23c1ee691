// LcmLogReader/LcmLogWriter: our log files are liblcm's (its lcm_eventlog, which lcm-logger writes with,
// reads what we write, and we read what it writes, byte for byte); a toposlamd run's messages come back as a
// LoggedRun; a truncated or corrupt log is an error naming the byte offset of the bad event.
#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <lcm/eventlog.h>

#include "toposlam/platform/lcm_log.hpp"
#include "toposlam/platform/lcm_log_run.hpp"
#include "toposlam_lcm/place_event_t.hpp"
#include "toposlam_lcm/place_t.hpp"
#include "toposlam_lcm/place_v1_t.hpp"
#include "toposlam_lcm/topology_t.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

std::string logPath(const std::string& name) {
  const fs::path dir = fs::path(TOPOSLAM_BINARY_DIR) / "tests" / "platform";
  fs::create_directories(dir);
  return (dir / name).string();
}

template <typename Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  return bytes;
}

std::string readBytes(const std::string& path) {
  std::string bytes;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char chunk[4096];
    for (std::size_t n; (n = std::fread(chunk, 1, sizeof chunk, f)) > 0;) bytes.append(chunk, n);
    std::fclose(f);
  }
  return bytes;
}

std::string errorOf(const std::string& path) {
  try {
    LcmLogReader reader(path);
    for (LcmLogEvent e; reader.next(e);) {
    }
  } catch (const LcmLogError& e) {
    return e.what();
  }
  return "";
}

/// A small run: frames 0..5, one place (frames 0..3, representative 2) on node 0, a topology.
std::string writeSmallRun(const std::string& name) {
  const std::string path = logPath(name);
  LcmLogWriter writer(path);
  for (int f = 0; f < 6; ++f) {
    toposlam_lcm::place_t p{};
    p.utime = 1'000'000 + 250'000 * f;
    p.frame = f;
    p.place = f >= 4 ? 0 : -1;
    p.node = f >= 4 ? 0 : -1;
    p.lambda2 = f == 0 ? std::nanf("") : 0.5f;
    p.match_frame = f == 5 ? 1 : -1;  // frame 5 is back at frame 1
    p.match_score = f == 5 ? 3.5f : 0.0f;
    p.match_place = f == 5 ? 0 : -1;
    p.match_node = f == 5 ? 0 : -1;
    if (f == 3) {  // as recorded before match_* existed
      toposlam_lcm::place_v1_t old{};
      old.utime = p.utime;
      old.frame = p.frame;
      old.lambda2 = p.lambda2;
      writer.write(5'000'000 + f, "TOPOSLAM_PLACE", encode(old).data(), encode(old).size());
      continue;
    }
    writer.write(5'000'000 + f, "TOPOSLAM_PLACE", encode(p).data(), encode(p).size());
    if (f == 4) {
      toposlam_lcm::place_event_t e{};
      e.place = 0;
      e.node = 0;
      e.is_new = true;
      e.probability = 1.0f;
      e.first_frame = 0;
      e.last_frame = 3;
      e.representative_frame = 2;
      e.keypoints = 42;
      e.jpeg_size = 3;
      e.jpeg = {0xFF, 0xD8, 0xFF};
      writer.write(5'000'000 + f, "TOPOSLAM_PLACE_EVENT", encode(e).data(), encode(e).size());
      toposlam_lcm::topology_t t{};
      t.probability = 0.75;
      t.particles = 100;
      t.num_nodes = 1;
      t.nodes.resize(1);
      t.nodes[0].id = 0;
      t.nodes[0].num_places = 1;
      t.nodes[0].places = {0};
      t.nodes[0].num_representatives = 1;
      t.nodes[0].representative_frames = {2};
      writer.write(5'000'000 + f, "TOPOSLAM_TOPOLOGY", encode(t).data(), encode(t).size());
    }
  }
  writer.write(6'000'000, "SOMEONE_ELSE", "x", 1);
  writer.close();
  return path;
}

}  // namespace

TEST_CASE("GIVEN a log written by liblcm's eventlog WHEN read by LcmLogReader THEN every event is the same, and "
          "liblcm reads ours",
          "[platform][lcm][lcmlog]") {
  const std::string theirs = logPath("liblcm.lcmlog");
  {
    lcm_eventlog_t* log = lcm_eventlog_create(theirs.c_str(), "w");
    REQUIRE(log != nullptr);
    for (int i = 0; i < 3; ++i) {
      std::string channel = "CHANNEL_" + std::to_string(i);
      std::vector<std::uint8_t> data(static_cast<std::size_t>(10 * i), static_cast<std::uint8_t>(i + 1));
      lcm_eventlog_event_t event{};
      event.timestamp = 1'700'000'000'000'000 + i;
      event.channellen = static_cast<std::int32_t>(channel.size());
      event.datalen = static_cast<std::int32_t>(data.size());
      event.channel = channel.data();
      event.data = data.data();
      REQUIRE(lcm_eventlog_write_event(log, &event) == 0);
    }
    lcm_eventlog_destroy(log);
  }
  LcmLogReader reader(theirs);
  std::vector<LcmLogEvent> events;
  for (LcmLogEvent e; reader.next(e);) events.push_back(e);
  REQUIRE(events.size() == 3);
  CHECK(events[2].event_number == 2);
  CHECK(events[2].utime == 1'700'000'000'000'002);
  CHECK(events[2].channel == "CHANNEL_2");
  CHECK(events[2].data == std::vector<std::uint8_t>(20, 3));
  CHECK(events[1].offset == 28 + 9);           // header + "CHANNEL_0", no data
  CHECK(reader.offset() == reader.size());

  // Ours, written the same way, is the same file byte for byte.
  const std::string ours = logPath("ours.lcmlog");
  {
    LcmLogWriter writer(ours);
    for (const LcmLogEvent& e : events) writer.write(e.utime, e.channel, e.data.data(), e.data.size());
    writer.close();
  }
  CHECK(readBytes(theirs).size() == reader.size());
  CHECK(readBytes(theirs) == readBytes(ours));
  lcm_eventlog_t* log = lcm_eventlog_create(ours.c_str(), "r");
  REQUIRE(log != nullptr);
  lcm_eventlog_event_t* first = lcm_eventlog_read_next_event(log);
  REQUIRE(first != nullptr);
  CHECK(std::string(first->channel) == "CHANNEL_0");
  lcm_eventlog_free_event(first);
  lcm_eventlog_destroy(log);
}

TEST_CASE("GIVEN a log of a toposlamd run WHEN read as a LoggedRun THEN frames, places and the topology come back",
          "[platform][lcm][lcmlog]") {
  const LoggedRun run = readLoggedRun(writeSmallRun("run.lcmlog"), LcmChannels{});
  CHECK(run.events == 9);
  CHECK(run.other_events == 1);
  CHECK(run.malformed == 0);
  REQUIRE(run.frames.size() == 6);
  CHECK(run.frames[5].frame == 5);
  CHECK(run.frames[5].time_s == Approx(2.25));
  CHECK(std::isnan(run.frames[0].lambda2));
  CHECK(run.frames[1].lambda2 == Approx(0.5));
  CHECK((run.frames[3].frame == 3 && run.frames[3].time_s == Approx(1.75)));  // the old message
  CHECK(run.frames[3].match_frame == -1);
  CHECK((run.frames[5].match_frame == 1 && run.frames[5].match_score == Approx(3.5) && run.frames[5].match_node == 0));
  REQUIRE(run.places.size() == 1);
  CHECK(run.places[0].representative_frame == 2);
  CHECK(run.places[0].keypoints == 42);
  CHECK(run.places[0].thumbnail_jpeg.size() == 3);
  REQUIRE(run.topology.has_value());
  CHECK(run.topology->probability == 0.75);
  CHECK(run.topology->nodes.at(0).places == std::vector<int>{0});
}

TEST_CASE("GIVEN a truncated or corrupt log WHEN read THEN the error names the file and the byte offset",
          "[platform][lcm][lcmlog][reliability]") {
  const std::string good = writeSmallRun("good.lcmlog");
  const std::string bytes = readBytes(good);
  LcmLogReader reader(good);
  LcmLogEvent e;
  REQUIRE(reader.next(e));
  const std::uint64_t second = reader.offset();  // where the second event starts
  auto write = [](const std::string& path, const std::string& content) {
    std::ofstream(path, std::ios::binary) << content;
    return path;
  };
  SECTION("cut inside the second event's header") {
    const std::string path = write(logPath("cut-header.lcmlog"), bytes.substr(0, second + 10));
    CHECK(errorOf(path) == path + ": truncated: an event header needs 28 bytes, only 10 are left (the log was cut short) "
                                  "(event 1 at byte " + std::to_string(second) + " of " + std::to_string(second + 10) + ")");
  }
  SECTION("cut inside the second event's data") {
    const std::string path = write(logPath("cut-data.lcmlog"), bytes.substr(0, second + 40));
    CHECK(errorOf(path).find("truncated: the event announces 14 bytes of channel name and ") != std::string::npos);
    CHECK(errorOf(path).find("only 12 are left (the log was cut short) (event 1 at byte " + std::to_string(second)) !=
          std::string::npos);
  }
  SECTION("a damaged sync word") {
    std::string damaged = bytes;
    damaged[second] = 'X';
    const std::string path = write(logPath("bad-sync.lcmlog"), damaged);
    CHECK(errorOf(path) == path + ": no LCM sync word (0xEDA1DA01), found 0x58A1DA01: the log is corrupt here (event 1 "
                                  "at byte " + std::to_string(second) + " of " + std::to_string(bytes.size()) + ")");
  }
  SECTION("a negative data length") {
    std::string damaged = bytes;
    damaged[second + 24] = '\xFF';
    const std::string path = write(logPath("bad-length.lcmlog"), damaged);
    CHECK(errorOf(path).find("implausible data length -") != std::string::npos);
  }
  SECTION("not a log at all") {
    const std::string path = write(logPath("text.lcmlog"), "hello, this is text\n and more of it ........");
    CHECK(errorOf(path).find("found 0x68656C6C: not an LCM log (event 0 at byte 0 of") != std::string::npos);
  }
  SECTION("an empty file holds no events") { CHECK(errorOf(write(logPath("empty.lcmlog"), "")).empty()); }
  SECTION("a missing file") { CHECK(errorOf(logPath("absent.lcmlog")).find("cannot open the LCM log") != std::string::npos); }
}
