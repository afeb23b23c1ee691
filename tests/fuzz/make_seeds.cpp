// Writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>/) from real encoders, so a seed
// is a valid input the fuzzer mutates from. Run once by hand when a format changes:
//   build/tests/fuzz/fuzz_make_seeds tests/fuzz/corpus
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "topology/fake_similarity.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/firmware/emulator.hpp"
#include "toposlam/topology/map_store.hpp"
#include "toposlam_lcm/motion_t.hpp"
#include "toposlam_lcm/place_event_t.hpp"
#include "toposlam_lcm/place_t.hpp"
#include "toposlam_lcm/status_t.hpp"
#include "toposlam_lcm/topology_t.hpp"

namespace fs = std::filesystem;

namespace {

void write(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

template <typename Message>
std::string encoded(char kind, const Message& m) {
  std::string bytes(static_cast<std::size_t>(m.getEncodedSize()), '\0');
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return std::string(1, kind) + bytes;
}

// "Billion laughs" in YAML: a0 lists ten x, each next level ten aliases of the one before (1e9 leaves at a8).
std::string configAliasBomb() {
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level < 9; ++level) {
    const std::string name = std::to_string(level), before = std::to_string(level - 1);
    bomb.append("a").append(name).append(": &a").append(name).append(" [");
    for (int i = 0; i < 10; ++i) bomb.append(i ? ", *a" : "*a").append(before);
    bomb += "]\n";
  }
  return bomb;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const fs::path out(argv[1]);
  using namespace toposlam;

  // Map files: a small filter, as a whole file (mode byte 0) and as a bare payload (mode byte 1).
  auto similarity = test::placeSimilarity();
  TopologyFilterConfig config;
  config.particles = 8;
  TopologyParticleFilter filter(config, similarity);
  for (int k = 0; k < 5; ++k) filter.step(test::taggedFingerprint(k % 3));
  const std::string file = MapStore::encode(filter, "toposlamd-frames 1 2 3", MapSettings{{"keypoints", "orb"}});
  write(out / "map_file" / "whole", std::string(1, '\0') + file);
  write(out / "map_file" / "payload", std::string(1, '\1') + file.substr(32));
  TopologyParticleFilter empty(config, similarity);
  write(out / "map_file" / "empty", std::string(1, '\0') + MapStore::encode(empty));

  // Configs: the shipped one and a few small ones.
  write(out / "config" / "small", "source: images:frames\nmap:\n  path: m.tsm\n  save_period_s: 5\n");
  write(out / "config" / "nested", "pipeline:\n  queues: {frames: 4, overflow: block}\ntopology: {particles: 50}\n");
  write(out / "config" / "two_documents", "source: images:a\n---\nsource: images:b\n");
  // Aliases, all refused before the document is built (issue 41): a billion-laughs bomb (nine levels of
  // ten aliases, 1e9 leaves if expanded), aliases of aliases, merge keys, an alias as a key, an alias of
  // nothing, and an alias in a second document; an anchor alone is harmless.
  write(out / "config" / "alias_bomb", configAliasBomb());
  write(out / "config" / "alias_nested",
        "q: &q {frames: 4, overflow: block}\nqueues: &queues {queues: *q}\npipeline: *queues\n");
  write(out / "config" / "alias_merge_key",
        "base: &base {particles: 50, seed: 3}\ntopology:\n  <<: *base\n  particles: 60\n");
  write(out / "config" / "alias_merge_list",
        "a: &a {particles: 50}\nb: &b {seed: 3}\ntopology:\n  <<: [*a, *b]\n");
  write(out / "config" / "alias_as_key", "k: &k source\n*k : images:frames\n");
  write(out / "config" / "alias_undefined", "topology: *nowhere\n");
  write(out / "config" / "alias_second_document", "source: images:a\n---\nx: &x 1\ny: *x\n");
  write(out / "config" / "anchor_only", "topology: &t {particles: 50}\n");
  // Octal-looking numbers (YAML 1.1 reads 010 as 8): refused with a leading zero, others as not integers.
  write(out / "config" / "octal_leading_zero", "topology: {particles: 010}\n");
  write(out / "config" / "octal_signed", "pipeline:\n  queues: {frames: -010}\ntopology: {particles: +010}\n");
  write(out / "config" / "octal_0o", "topology: {particles: 0o10}\n");
  write(out / "config" / "hexadecimal", "topology: {particles: 0x10}\n");
  write(out / "config" / "real_leading_zero", "segmentation: {window_s: 06.5}\n");

  // Fingerprints of a real frame, with ORB and SIFT keypoints.
  const cv::Mat frame = cv::imread(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples/1.jpg", cv::IMREAD_COLOR);
  for (KeypointBackend backend : {KeypointBackend::Orb, KeypointBackend::Sift}) {
    VpackConfig vpack;
    vpack.keypoints.backend = backend;
    vpack.keypoints.max_keypoints = 12;
    std::ostringstream bytes;
    writeFingerprint(bytes, VpackExtractor(vpack).extract(frame));
    write(out / "fingerprint" / toString(backend), bytes.str());
  }

  // Image headers: tiny PNG, JPEG and BMP files.
  const cv::Mat small = cv::Mat(6, 9, CV_8UC3, cv::Scalar(20, 120, 220));
  for (const char* ext : {".png", ".jpg", ".bmp"}) {
    std::vector<unsigned char> bytes;
    cv::imencode(ext, small, bytes);
    write(out / "image_header" / (std::string("small") + ext), std::string(bytes.begin(), bytes.end()));
  }

  // LCM messages, one of each type (byte 0 selects the type in the harness).
  toposlam_lcm::place_t place{};
  place.num_alternatives = 2;
  place.alternatives.resize(2);
  write(out / "lcm_messages" / "place", encoded('\0', place));
  toposlam_lcm::place_event_t event{};
  event.jpeg_size = 4;
  event.jpeg = {0xFF, 0xD8, 0xFF, 0xD9};
  write(out / "lcm_messages" / "place_event", encoded('\1', event));
  toposlam_lcm::status_t status{};
  status.state = "running";
  status.source_state = "streaming";
  status.num_stages = 1;
  status.stages.resize(1);
  status.stages[0].name = "capture";
  write(out / "lcm_messages" / "status", encoded('\2', status));
  toposlam_lcm::topology_t topology{};
  topology.num_nodes = 1;
  topology.nodes.resize(1);
  topology.nodes[0].num_places = 1;
  topology.nodes[0].places = {0};
  topology.nodes[0].num_representatives = 1;
  topology.nodes[0].representative_frames = {3};
  write(out / "lcm_messages" / "topology", encoded('\3', topology));
  write(out / "lcm_messages" / "motion", encoded('\4', toposlam_lcm::motion_t{}));
  // Motion input (records of [receiver clock step in 10 ms, length, motion_t]): 1 s of a robot driving at
  // 0.5 m/s at 50 Hz on the receiver's clock (which starts at 1000 s), clean, with one message stamped by
  // Unix time, and with an absurd one (945 km forward, 4.3 million rad/s).
  {
    auto motionRun = [](int poison_at, const toposlam_lcm::motion_t& poison) {
      std::string seed;
      for (int i = 0; i < 50; ++i) {
        toposlam_lcm::motion_t m{};
        m.utime = static_cast<std::int64_t>((1000.0 + 0.02 * (i + 1)) * 1e6);
        m.sequence = i;
        m.forward_m = 0.01;
        m.linear_velocity_mps = 0.5;
        m.moving = 1;
        if (i == poison_at) {
          m = poison;
          m.utime = poison.utime != 0 ? poison.utime : static_cast<std::int64_t>((1000.0 + 0.02 * (i + 1)) * 1e6);
          m.sequence = i;
        }
        const std::string bytes = encoded('\2', m);  // byte 0: the clock step (20 ms), then the length
        seed += bytes.substr(0, 1) + std::string(1, static_cast<char>(bytes.size() - 1)) + bytes.substr(1);
      }
      return seed;
    };
    write(out / "motion_input" / "driving", motionRun(-1, {}));
    toposlam_lcm::motion_t future{};
    future.utime = 1'700'000'000'000'000;
    write(out / "motion_input" / "unix-time-stamped", motionRun(20, future));
    toposlam_lcm::motion_t absurd{};
    absurd.forward_m = 945000.0;
    absurd.angular_velocity_rps = 4.3e6;
    write(out / "motion_input" / "absurd", motionRun(20, absurd));
  }
  // Controller links: 1.5 s of each emulated message set (byte 0: protocol, byte 1: piece sizes), clean
  // and damaged.
  {
    using namespace toposlam::firmware;
    const struct {
      const char* name;
      EmulatedMessages messages;
      char protocol;
      double damage;
    } links[] = {{"wheel-odometry", EmulatedMessages::WheelOdometry, '\0', 0.0},
                 {"wheel-body-velocity-damaged", EmulatedMessages::BodyVelocity, '\0', 0.1},
                 {"mavlink-odometry", EmulatedMessages::MavlinkOdometry, '\1', 0.0},
                 {"mavlink-local-position-damaged", EmulatedMessages::MavlinkLocalPosition, '\1', 0.1}};
    for (const auto& l : links) {
      EmulatorConfig c;
      c.messages = l.messages;
      c.rate_hz = 20;
      c.profile = {{0.75, 0.5, 0.2}, {0.75, 0.0, 0.0}};
      c.corrupt_probability = l.damage;
      c.garbage_probability = l.damage;
      c.other_mavlink_traffic = l.protocol == '\1';
      ControllerEmulator emulator(c);
      std::vector<std::uint8_t> bytes;
      emulator.advanceTo(emulator.duration(), bytes);
      std::string seed{l.protocol, '\x11'};
      seed.append(bytes.begin(), bytes.end());
      write(out / "firmware_link" / l.name, seed);
    }
  }
  return 0;
}
