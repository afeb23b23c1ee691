// End to end: toposlamd on the simulated two-traversal office, heard over real LCM UDP multicast (run by
// in_netns.sh inside a private network namespace). Checks the place messages (nodes map to rooms, the loop
// is closed), READY/WATCHDOG on a fake NOTIFY_SOCKET, and that SIGTERM mid-run saves a map that resumes.
#include <catch2/catch.hpp>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include "e2e_harness.hpp"
#include "platform/lcm/lcm_fragment_sender.hpp"
#include "toposlam/io/sim_source.hpp"
#include "toposlam/io/source_uri.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include <lcm/lcm-cpp.hpp>

#include "toposlam_lcm/motion_t.hpp"

namespace fs = std::filesystem;
using namespace toposlam;
using e2e::freshDirectory;
using e2e::Heard;
using e2e::integerField;
using e2e::listenUntilExit;
using e2e::numberField;

namespace {

const std::string kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
const std::string kRoute = "sim:office?route=loop2";

/// A unix datagram socket standing in for systemd's notify socket (non-blocking reads).
class FakeNotifySocket {
 public:
  explicit FakeNotifySocket(const fs::path& path) : path_(path.string()) {
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    path_.copy(address.sun_path, sizeof(address.sun_path) - 1);
    if (fd_ < 0 || bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
      throw std::runtime_error("cannot bind " + path_);
  }
  ~FakeNotifySocket() { close(fd_); }
  /// Everything received so far, one datagram per entry.
  std::vector<std::string> drain() {
    std::vector<std::string> out;
    char buffer[4096];
    for (ssize_t n; (n = recv(fd_, buffer, sizeof buffer, 0)) > 0;) out.emplace_back(buffer, static_cast<std::size_t>(n));
    return out;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

/// toposlamd as a child process, its output in `log`; with `notify_socket`, started as systemd would (a 1 s
/// watchdog).
class Daemon : public e2e::ChildProcess {
 public:
  Daemon(const std::vector<std::string>& args, const std::string& notify_socket, const fs::path& log)
      : ChildProcess(TOPOSLAMD_BINARY, args, options(notify_socket, log)) {}

 private:
  static Options options(const std::string& notify_socket, const fs::path& log) {
    Options o;
    o.log_file = log;
    if (!notify_socket.empty()) {
      o.environment = {{"NOTIFY_SOCKET", notify_socket}, {"WATCHDOG_USEC", "1000000"}};
      o.pid_variable = "WATCHDOG_PID";
    }
    return o;
  }
};

std::unique_ptr<LcmSubscriber> subscribe(Heard& heard) { return e2e::subscribe(kLcmUrl, heard); }

bool contains(const std::vector<std::string>& lines, const std::string& text) {
  for (const std::string& l : lines)
    if (l.find(text) != std::string::npos) return true;
  return false;
}

/// Representative frame of a place event, from its JSON.
std::int64_t representativeOf(const ReceivedMessage& m) { return integerField(m, "representative_frame"); }

/// One row of `toposlam map`'s places.csv: first, last, representative frame and node.
struct OfflinePlace {
  std::int64_t first = -1, last = -1, representative = -1, node = -1;
};

/// Runs `toposlam map URI --out DIR` (the offline data path) and reads its places.csv; empty on failure.
std::vector<OfflinePlace> offlineMap(const std::string& uri, const fs::path& dir) {
  const std::string command = std::string(TOPOSLAM_CLI_BINARY) + " map '" + uri + "' --out '" + dir.string() +
                              "' > '" + (dir.string() + ".log") + "' 2>&1";
  std::vector<OfflinePlace> places;
  if (std::system(command.c_str()) != 0) return places;
  std::ifstream in(dir / "places.csv");
  std::string line;
  std::getline(in, line);  // place,first,last,representative,keypoints,node,end
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::string cell;
    std::vector<std::int64_t> v;
    while (v.size() < 6 && std::getline(row, cell, ',')) v.push_back(std::stoll(cell));
    if (v.size() == 6) places.push_back(OfflinePlace{v[1], v[2], v[3], v[5]});
  }
  return places;
}

/// Place -> node of a TOPOSLAM_TOPOLOGY message, from its JSON ("nodes":[{"id":N,"places":[...]},...]).
/// (A plain scan: GCC 12 with sanitizers warns falsely inside std::regex.)
std::map<int, int> nodesOfPlaces(const ReceivedMessage& topology) {
  std::map<int, int> node_of_place;
  const std::string& json = topology.json;
  const std::string id_key = "{\"id\":", places_key = ",\"places\":[";
  for (std::size_t at = json.find(id_key); at != std::string::npos; at = json.find(id_key, at + 1)) {
    const std::size_t id_end = json.find(places_key, at);
    if (id_end == std::string::npos) break;
    const int node = std::stoi(json.substr(at + id_key.size(), id_end - at - id_key.size()));
    const std::size_t list = id_end + places_key.size();
    std::istringstream places(json.substr(list, json.find(']', list) - list));
    for (std::string place; std::getline(places, place, ',');) node_of_place[std::stoi(place)] = node;
  }
  return node_of_place;
}

}  // namespace

/// One run of toposlamd over the whole route, shared by the sections below (Catch re-enters the scenario
/// once per THEN; the daemon runs once).
struct OfficeRun {
  int code = -1;
  bool map_saved = false;
  std::vector<std::string> notifications;
  Heard heard;
  std::int64_t frames = 0;
  std::vector<int> event_rooms;  ///< ground-truth room of each place event's representative (-1: doorway)
  std::vector<int> event_traversals;  ///< traversal (0, 1) of each place event's representative
};

const OfficeRun& officeRun() {
  static const OfficeRun run = [] {
    OfficeRun r;
    const fs::path dir = freshDirectory("office");
    FakeNotifySocket notify(dir / "notify.sock");
    auto subscriber = subscribe(r.heard);
    Daemon daemon({"--source", kRoute + "&rate=250", "--overflow", "block", "--map", (dir / "map.tsm").string(),
                   "--no-map-load", "--lcm-url", kLcmUrl},
                  notify.path(), dir / "toposlamd.log");
    r.code = listenUntilExit(*subscriber, daemon, 100.0, [&] {
      for (std::string& n : notify.drain()) r.notifications.push_back(std::move(n));
    });
    for (std::string& n : notify.drain()) r.notifications.push_back(std::move(n));
    r.map_saved = fs::exists(dir / "map.tsm");
    sim::Simulator truth(simConfigFromUri(parseSourceUri(kRoute)));
    r.frames = truth.frameCount();
    for (const ReceivedMessage& e : r.heard.events) {
      const sim::GroundTruth t = truth.truthOf(representativeOf(e));
      r.event_rooms.push_back(t.room);
      r.event_traversals.push_back(t.traversal);
    }
    return r;
  }();
  return run;
}

SCENARIO("toposlamd maps the simulated two-traversal office and publishes it over LCM multicast") {
  GIVEN("toposlamd on sim:office?route=loop2 (lossless queues), a fake NOTIFY_SOCKET with a 1 s watchdog") {
    const OfficeRun& run = officeRun();
    const Heard& heard = run.heard;
    THEN("it ran to the end of the route, exited 0 and saved the map") {
      CHECK(run.code == 0);
      CHECK(run.map_saved);
    }
    THEN("systemd would have seen READY=1, STATUS= lines and watchdog pings") {
      CHECK(contains(run.notifications, "READY=1"));
      CHECK(contains(run.notifications, "STATUS=running"));
      CHECK(contains(run.notifications, "WATCHDOG=1"));
    }
    THEN("the end of the route (no signal) was announced with STOPPING=1 after READY=1") {
      const auto ready = std::find(run.notifications.begin(), run.notifications.end(), "READY=1");
      const auto stopping = std::find(run.notifications.begin(), run.notifications.end(), "STOPPING=1");
      CHECK(ready != run.notifications.end());
      CHECK(stopping != run.notifications.end());
      CHECK(ready < stopping);
    }
    THEN("a place message arrived for (nearly) every frame, in order") {
      // UDP may lose a datagram under load; the daemon itself drops nothing in block mode.
      CHECK(static_cast<double>(heard.places.size()) >= 0.95 * static_cast<double>(run.frames));
      for (std::size_t i = 1; i < heard.places.size(); ++i) CHECK(heard.places[i].frame > heard.places[i - 1].frame);
      REQUIRE_FALSE(heard.statuses.empty());
      CHECK_THAT(heard.statuses.back().json, Catch::Contains("\"state\":\"finished\""));
    }
    THEN("places map to rooms: each node's places are mostly one room, and the loop is closed") {
      REQUIRE(heard.events.size() >= 8);
      CHECK_THAT(heard.events.front().json, Catch::Contains("\"place\":0,\"node\":0,\"is_new\":true"));
      std::map<int, std::map<int, int>> rooms_of_node;  // node -> room -> places
      std::map<int, int> first_room_of_node;
      int revisits = 0, revisits_same_room = 0, labelled = 0;
      for (std::size_t i = 0; i < heard.events.size(); ++i) {
        const ReceivedMessage& e = heard.events[i];
        const int room = run.event_rooms[i];
        if (room < 0) continue;  // representative in a doorway
        ++labelled;
        ++rooms_of_node[e.node][room];
        if (!e.is_new) {
          ++revisits;
          if (first_room_of_node.count(e.node) && first_room_of_node[e.node] == room) ++revisits_same_room;
        }
        first_room_of_node.emplace(e.node, room);
      }
      int majority = 0;
      for (const auto& [node, rooms] : rooms_of_node) {
        int best = 0;
        for (const auto& [room, count] : rooms) best = std::max(best, count);
        majority += best;
      }
      INFO("places with a room label: " << labelled << ", in their node's majority room: " << majority
                                        << ", revisits: " << revisits << " (" << revisits_same_room << " same room)");
      CHECK(static_cast<double>(majority) >= 0.8 * labelled);
      CHECK(revisits >= 3);                          // the second traversal re-used nodes
      CHECK(2 * revisits_same_room >= revisits);     // at least half of them in the room the node was made in
    }
    THEN("the loop is closed on the second traversal: in the final topology its places are on first-traversal "
         "nodes of their room") {
      // Measured: 6 of 7 closed, 0 wrong. Offline (doorway representatives counted by their place's
      // majority room) the same route gives 12 of 12 and no wrong node
      // (tests/segmentation/test_offline_mapping.cpp). The per-event node is the filter's estimate at that
      // step; the final topology (the last TOPOSLAM_TOPOLOGY message) is the one with hindsight.
      REQUIRE_FALSE(heard.topologies.empty());
      const std::map<int, int> node_of_place = nodesOfPlaces(heard.topologies.back());
      std::map<int, std::set<int>> first_traversal_rooms_of_node;
      std::set<int> first_traversal_rooms;
      std::vector<std::pair<int, int>> second_places;  // (node, room) of second-traversal places
      for (std::size_t i = 0; i < heard.events.size(); ++i) {
        const int room = run.event_rooms[i];
        const auto node = node_of_place.find(heard.events[i].place);
        if (room < 0 || node == node_of_place.end()) continue;  // representative in a doorway
        if (run.event_traversals[i] == 0) {
          first_traversal_rooms_of_node[node->second].insert(room);
          first_traversal_rooms.insert(room);
        } else if (first_traversal_rooms.count(room) > 0) {
          second_places.emplace_back(node->second, room);
        }
      }
      int closed = 0, wrong = 0;
      for (const auto& [node, room] : second_places) {
        const auto rooms = first_traversal_rooms_of_node.find(node);
        if (rooms == first_traversal_rooms_of_node.end()) continue;  // a new node: a missed closure
        (rooms->second.count(room) > 0 ? closed : wrong) += 1;
      }
      INFO("second traversal: " << second_places.size() << " places in rooms seen before, " << closed
                                << " on a first-traversal node of their room, " << wrong << " on another room's node");
      // Measured with the default preset (the segmentation window on the frames' source time): 10 places in
      // rooms seen before, 8 closed, 0 on another room's node. The thesis-era defaults closed 6 of 7 here
      // but no loop at all on real frames.
      REQUIRE(second_places.size() >= 6);
      CHECK(closed >= static_cast<int>(second_places.size()) - 3);
      CHECK(wrong <= 1);
    }
    THEN("the daemon found the places and nodes that `toposlam map` finds offline on the same frames") {
      // One data path (docs/architecture.md): the same segmenter and the same seeded filter, here sliced over
      // frames on the topology thread, there stepped whole. Place borders, representatives and the final
      // most probable topology must agree exactly.
      const std::vector<OfflinePlace> offline = offlineMap(kRoute, freshDirectory("office-offline"));
      REQUIRE_FALSE(offline.empty());
      REQUIRE(heard.events.size() == offline.size());
      for (std::size_t p = 0; p < offline.size(); ++p) {
        INFO("place " << p);
        CHECK(integerField(heard.events[p], "place") == static_cast<std::int64_t>(p));
        CHECK(integerField(heard.events[p], "first_frame") == offline[p].first);
        CHECK(integerField(heard.events[p], "last_frame") == offline[p].last);
        CHECK(representativeOf(heard.events[p]) == offline[p].representative);
      }
      REQUIRE_FALSE(heard.topologies.empty());
      const std::map<int, int> node_of_place = nodesOfPlaces(heard.topologies.back());
      for (std::size_t p = 0; p < offline.size(); ++p) {
        INFO("place " << p);
        const auto it = node_of_place.find(static_cast<int>(p));
        REQUIRE(it != node_of_place.end());
        CHECK(it->second == offline[p].node);
      }
    }
  }
}

SCENARIO("SIGTERM mid-run saves the map, and the next start resumes from it") {
  GIVEN("toposlamd stopped by SIGTERM after its third place") {
    const fs::path dir = freshDirectory("resume");
    const fs::path map = dir / "map.tsm";
    Heard first;
    int code = -1;
    {
      auto subscriber = subscribe(first);
      Daemon daemon({"--source", kRoute + "&rate=150", "--overflow", "block", "--map", map.string(), "--no-map-load",
                     "--lcm-url", kLcmUrl},
                    "", dir / "first.log");
      bool sent = false;
      code = listenUntilExit(*subscriber, daemon, 100.0, [&] {
        if (!sent && first.events.size() >= 3) {
          daemon.terminate();
          sent = true;
        }
      });
    }
    THEN("it exits 0 before the end of the route, with every closed place stepped and the map saved") {
      CHECK(code == 0);
      REQUIRE(fs::exists(map));
      REQUIRE_FALSE(first.statuses.empty());
      CHECK_THAT(first.statuses.back().json, Catch::Contains("\"maps_saved\":1"));
      CHECK(first.places.size() < 1600);
    }
    WHEN("toposlamd starts again with the same map") {
      Heard second;
      auto subscriber = subscribe(second);
      Daemon daemon({"--source", kRoute + "&rate=250", "--overflow", "block", "--map", map.string(), "--lcm-url",
                     kLcmUrl},
                    "", dir / "second.log");
      bool sent = false;
      const int second_code = listenUntilExit(*subscriber, daemon, 100.0, [&] {
        if (!sent && !second.events.empty()) {
          daemon.terminate();
          sent = true;
        }
      });
      THEN("place numbering continues from the saved map and the start room is recognised") {
        CHECK(second_code == 0);
        REQUIRE_FALSE(second.events.empty());
        const int saved_places = static_cast<int>(first.events.size());
        CHECK(second.events.front().place == saved_places);
        // The route starts in the same room again: its node is one the saved map already had.
        CHECK_FALSE(second.events.front().is_new);
        CHECK(second.events.front().node == first.events.front().node);
      }
    }
  }
}

SCENARIO("Robot motion over LCM: the status says it is used while it arrives, and lost once it stops") {
  GIVEN("toposlamd on the simulated office at 25 fps and a robot node publishing motion_t: standing for 4 s") {
    const fs::path dir = freshDirectory("motion");
    Heard heard;
    auto subscriber = subscribe(heard);
    auto robot = openLcm(kLcmUrl);
    Daemon daemon({"--source", kRoute + "&rate=25", "--overflow", "block", "--map", (dir / "map.tsm").string(),
                   "--no-map-load", "--lcm-url", kLcmUrl},
                  "", dir / "toposlamd.log");
    // Motion starts after the first status (the daemon's LCM is up), every 50 ms, for 4 s.
    const auto started = std::chrono::steady_clock::now();
    std::optional<std::chrono::steady_clock::time_point> motion_from, next_sample;
    std::int64_t sequence = 0, first_sample_us = -1, last_sample_us = -1;
    bool sent_stop = false;
    const int code = listenUntilExit(*subscriber, daemon, 60.0, [&] {
      const auto now = std::chrono::steady_clock::now();
      if (!motion_from && !heard.statuses.empty()) motion_from = next_sample = now;
      // On a 50 ms schedule, not once per loop: the subscriber hears these messages too, and each one
      // heard ends a wait early.
      if (motion_from && now - *motion_from < std::chrono::seconds(4) && now >= *next_sample) {
        *next_sample += std::chrono::milliseconds(50);
        toposlam_lcm::motion_t m{};
        m.utime = monotonicMicroseconds();
        if (first_sample_us < 0) first_sample_us = m.utime;
        last_sample_us = m.utime;
        m.sequence = sequence++;
        m.moving = false;  // standing: no distance, no speed, no turn
        robot->publish(LcmChannels{}.motion, &m);
      }
      // Stop once a status reports the link lost (or give up after 30 s).
      const bool lost = !heard.statuses.empty() &&
                        heard.statuses.back().json.find("\"motion_state\":\"lost\"") != std::string::npos;
      if (!sent_stop && (lost || now - started > std::chrono::seconds(30))) {
        daemon.terminate();
        sent_stop = true;
      }
    });
    THEN("a status first says none, then used with standing frames skipped, then lost; the daemon exits 0") {
      CHECK(code == 0);
      REQUIRE(sequence > 40);
      REQUIRE_FALSE(heard.statuses.empty());
      const e2e::MotionStatusHistory status = e2e::motionStatusHistory(heard.statuses);
      INFO("first status " << heard.statuses.front().json);
      INFO("last status " << heard.statuses.back().json);
      CHECK(status.first_says_none);
      CHECK(status.first_used >= 0);
      CHECK(status.first_lost > status.first_used);
      // Standing from 1 s after the first sample (standing_after_s) until the link is declared lost 1 s after
      // the last one (timeout_s): 4 s, 100 frames at 25 fps (measured: 100). A loaded machine (sanitizers)
      // captures fewer or bunched frames, so the expectation is the frames captured in that interval, from
      // the place messages' capture times.
      const std::int64_t expected =
          e2e::framesCapturedIn(heard.places, static_cast<double>(first_sample_us + 1'000'000),
                                static_cast<double>(last_sample_us + 1'000'000));
      const std::int64_t standing = status.standing_frames;
      INFO("standing frames " << standing << ", frames captured while standing " << expected);
      CHECK(standing >= 25);
      CHECK(std::abs(standing - expected) <= std::max<std::int64_t>(5, expected / 10));
      // Every message sent was heard (UDP on loopback may lose one under load).
      const std::int64_t received = status.messages;
      REQUIRE(received >= 0);
      CHECK(received <= sequence);
      CHECK(received >= sequence - sequence / 20);
    }
  }
}

SCENARIO("One motion message stamped with the wall clock among the robot's: refused and counted, the stop still seen; "
         "two messages that are not motion_t counted as malformed, two fragmented ones left unfinished as "
         "abandoned") {
  GIVEN("toposlamd on the simulated office at 25 fps and a robot node standing for 4 s, with one message in Unix time") {
    const fs::path dir = freshDirectory("motion-wall-clock");
    Heard heard;
    auto subscriber = subscribe(heard);
    auto robot = openLcm(kLcmUrl);
    const test::MulticastSender fragment_sender(kLcmUrl);
    Daemon daemon({"--source", kRoute + "&rate=25", "--overflow", "block", "--map", (dir / "map.tsm").string(),
                   "--no-map-load", "--lcm-url", kLcmUrl},
                  "", dir / "toposlamd.log");
    const auto started = std::chrono::steady_clock::now();
    std::optional<std::chrono::steady_clock::time_point> motion_from, next_sample;
    std::int64_t sequence = 0, first_sample_us = -1, last_sample_us = -1;
    bool sent_stop = false;
    const int code = listenUntilExit(*subscriber, daemon, 60.0, [&] {
      const auto now = std::chrono::steady_clock::now();
      if (!motion_from && !heard.statuses.empty()) motion_from = next_sample = now;
      if (motion_from && now - *motion_from < std::chrono::seconds(4) && now >= *next_sample) {
        *next_sample += std::chrono::milliseconds(50);
        toposlam_lcm::motion_t m{};
        m.utime = monotonicMicroseconds();
        if (first_sample_us < 0) first_sample_us = m.utime;
        last_sample_us = m.utime;
        m.sequence = sequence++;
        robot->publish(LcmChannels{}.motion, &m);
        if (sequence == 10) {  // 0.5 s in: a node stamping utime with the wall clock (about 1.8e15 us)
          toposlam_lcm::motion_t wall = m;
          wall.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::system_clock::now().time_since_epoch())
                           .count();
          robot->publish(LcmChannels{}.motion, &wall);
          // ... and two messages that are not motion_t at all (a node publishing another type on the channel).
          const std::string garbage = "not a motion_t";
          for (int i = 0; i < 2; ++i)
            robot->publish(LcmChannels{}.motion, garbage.data(), static_cast<unsigned int>(garbage.size()));
          // ... and two fragmented messages from one node that lose fragments: the first superseded by the
          // second, the second never finished (abandoned after 2 s of silence).
          const std::vector<std::uint8_t> payload(3000, 0x5A);
          const auto first = test::lcmFragments(LcmChannels{}.motion, payload, 1, 3);
          const auto second = test::lcmFragments(LcmChannels{}.motion, payload, 2, 3);
          for (const auto* datagram : {&first[0], &first[2], &second[0], &second[1]})
            fragment_sender.send(*datagram);
        }
      }
      const bool lost = !heard.statuses.empty() &&
                        heard.statuses.back().json.find("\"motion_state\":\"lost\"") != std::string::npos;
      if (!sent_stop && (lost || now - started > std::chrono::seconds(30))) {
        daemon.terminate();
        sent_stop = true;
      }
    });
    THEN("the message is refused and counted; the robot's samples are still used, so its stop is seen") {
      CHECK(code == 0);
      REQUIRE(sequence > 40);
      REQUIRE_FALSE(heard.statuses.empty());
      const e2e::MotionStatusHistory status = e2e::motionStatusHistory(heard.statuses);
      INFO("last status " << heard.statuses.back().json);
      CHECK(status.refused == 1);
      CHECK(status.malformed == 2);
      CHECK(status.fragments_abandoned == 2);
      CHECK(status.first_used >= 0);
      CHECK(status.first_lost > status.first_used);
      // As in the scenario without the stray message: standing from 1 s after the first sample to 1 s after
      // the last (before issue 41's fix: about none, every sample after the stray one was "earlier").
      const std::int64_t expected =
          e2e::framesCapturedIn(heard.places, static_cast<double>(first_sample_us + 1'000'000),
                                static_cast<double>(last_sample_us + 1'000'000));
      const std::int64_t standing = status.standing_frames;
      INFO("standing frames " << standing << ", frames captured while standing " << expected);
      CHECK(standing >= 25);
      CHECK(std::abs(standing - expected) <= std::max<std::int64_t>(5, expected / 10));
      std::ostringstream log;
      log << std::ifstream(dir / "toposlamd.log").rdbuf();
      CHECK(log.str().find("motion sample refused: its time is further from the receiver's clock") != std::string::npos);
    }
  }
}
