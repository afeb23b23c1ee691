// DaemonConfig: the shipped config/toposlam.yaml equals the defaults in code; unknown keys, wrong types and
// out-of-range values are refused with the key's full dotted name and the allowed range.
#include <catch2/catch.hpp>

#include <chrono>
#include <fstream>
#include <sstream>

#include <string>
#include <utility>
#include <vector>

#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/daemon_config.hpp"

using namespace toposlam;

namespace {

std::string errorOf(const std::string& yaml) {
  try {
    parseDaemonConfig(yaml, "test.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string fileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

SCENARIO("The shipped config documents the defaults in code") {
  GIVEN("config/toposlam.yaml") {
    const DaemonConfig shipped = loadDaemonConfig(TOPOSLAM_SOURCE_DIR "/config/toposlam.yaml");
    const DaemonConfig defaults;
    THEN("it loads and every value equals the default in code") {
      CHECK(shipped.validate().empty());
      // The one exception: the installed service reads the camera, the built-in default is the simulator.
      CHECK(shipped.source == "v4l2:/dev/video0");
      CHECK(defaults.source == "sim:office?route=loop2");
      // Every other key, mechanically from the key table (test_config_keys checks the table itself).
      for (const ConfigKey& key : daemonConfigKeys()) {
        if (key.path == "source") continue;
        INFO(key.path);
        CHECK(key.get(shipped) == key.get(defaults));
      }
    }
  }
  GIVEN("an empty document") {
    THEN("it means all defaults") { CHECK(parseDaemonConfig("", "empty").source == DaemonConfig{}.source); }
  }
}

SCENARIO("Values given in the file override the defaults") {
  const DaemonConfig c = parseDaemonConfig(R"(
source: "images:/data/run1?rate=5"
record: {dir: /data/recordings, max_mb: 50, format: png, queue_frames: 4}
lcm: {url: "udpm://239.255.76.67:7667?ttl=1", channels: {place: ROBOT1_PLACE}}
map: {path: /var/lib/toposlam/office.tsm, save_period_s: 0, load_at_start: false}
pipeline:
  queues: {frames: 4, overflow: block}
  threads: {topology: {name: my-filter, cpu: 1, policy: fifo, priority: 20}}
  filter_budget_ms: 7.5
fingerprint: {workers: 1, keypoints: {backend: sift, max_keypoints: 200}}
segmentation: {window: 31, cut_placement: valley-frame}
topology: {particles: 200, seed: 42}
)");
  CHECK(c.source == "images:/data/run1?rate=5");
  CHECK(c.lcm.url == "udpm://239.255.76.67:7667?ttl=1");
  CHECK(c.lcm.place_channel == "ROBOT1_PLACE");
  CHECK(c.lcm.status_channel == "TOPOSLAM_STATUS");
  CHECK(c.map.path == "/var/lib/toposlam/office.tsm");
  CHECK(c.map.save_period_s == 0.0);
  CHECK_FALSE(c.map.load_at_start);
  CHECK(c.pipeline.queues.frames == 4);
  CHECK(c.pipeline.queues.overflow == QueueOverflow::Block);
  CHECK(c.pipeline.threads.topology.name == "my-filter");
  CHECK(c.pipeline.threads.topology.cpu == 1);
  CHECK(c.pipeline.threads.topology.policy == SchedulingPolicy::Fifo);
  CHECK(c.pipeline.threads.topology.priority == 20);
  CHECK(c.pipeline.filter_budget_ms == 7.5);
  CHECK(c.fingerprint_stage.workers == 1);
  CHECK(c.fingerprint.keypoints.backend == KeypointBackend::Sift);
  CHECK(c.fingerprint.keypoints.max_keypoints == 200);
  CHECK(c.segmentation.window == 31);
  CHECK(c.segmentation.cut_placement == CutPlacement::ValleyFrame);
  CHECK(c.topology.particles == 200);
  CHECK(c.topology.seed == 42u);
  CHECK(c.record.dir == "/data/recordings");
  CHECK(c.record.max_mb == 50.0);
  CHECK(c.record.format == "png");
  CHECK(c.record.queue_frames == 4);
  CHECK(c.record.jpeg_quality == 95);
}

SCENARIO("Bad configs are refused with the key's full name and the allowed range") {
  // (yaml, the error must contain this)
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"sourse: x", "unknown key 'sourse'"},
      {"pipeline: {queues: {framez: 2}}", "unknown key 'pipeline.queues.framez'"},
      {"pipeline: {threads: {capture: {prio: 1}}}", "unknown key 'pipeline.threads.capture.prio'"},
      {"pipeline: {threads: {gpu: {}}}", "unknown key 'pipeline.threads.gpu'"},
      {"pipeline: {queues: {frames: 0}}", "pipeline.queues.frames: 0 is out of range, allowed 1 .. 1024"},
      {"pipeline: {queues: {results: 5000}}", "pipeline.queues.results: 5000 is out of range, allowed 1 .. 1024"},
      {"record: {max_mb: 0}", "record.max_mb: 0 is out of range, allowed [1, 1e+07] MB"},
      {"record: {format: bmp}", "record.format: 'bmp' is not allowed, expected one of: jpg, png"},
      {"record: {jpeg_quality: 0}", "record.jpeg_quality: 0 is out of range, allowed 1 .. 100"},
      {"record: {queue_frames: 2000}", "record.queue_frames: 2000 is out of range, allowed 1 .. 1024 frames"},
      {"record: {directory: /tmp}", "unknown key 'record.directory'"},
      {"lcm: {open_retry_s: -1}", "lcm.open_retry_s: -1 is out of range, allowed [0, 3600] seconds (0 = exit 1 at once)"},
      {"log_level: verbose", "log_level: 'verbose' is not allowed, expected one of: trace, debug, info, warn, error"},
      {"pipeline: {queues: {overflow: drop_newest}}", "pipeline.queues.overflow: 'drop_newest' is not allowed, expected one of: auto, drop_oldest, block"},
      {"pipeline: {filter_budget_ms: 0}", "pipeline.filter_budget_ms: 0 is out of range, allowed [0.1, 1000] milliseconds"},
      {"pipeline: {status_period_s: 120}", "pipeline.status_period_s: 120 is out of range, allowed [0.1, 60] seconds"},
      {"pipeline: {thumbnail_width: 8}", "pipeline.thumbnail_width: 8 is out of range, allowed 16 .. 1280 pixels"},
      {"pipeline: {threads: {capture: {name: this-name-is-too-long}}}", "pipeline.threads.capture.name: must have 1 to 15 characters"},
      {"pipeline: {threads: {capture: {cpu: -5}}}", "pipeline.threads.capture.cpu: -5 is out of range, allowed -1 .. 1023"},
      {"pipeline: {threads: {publisher: {policy: fifo}}}", "pipeline.threads.publisher.priority: 0 is out of range for policy fifo, allowed 1 .. 99"},
      {"pipeline: {threads: {segmentation: {policy: rr}}}", "pipeline.threads.segmentation.policy: 'rr' is not allowed, expected one of: other, fifo"},
      {"map: {save_period_s: -1}", "map.save_period_s: -1 is out of range, allowed [0, 86400] seconds"},
      {"map: {save_period_s: 0.5}", "map.save_period_s: 0.5"},
      {"map: {load_at_start: maybe}", "map.load_at_start: expected true or false, got 'maybe'"},
      {"watchdog: {heartbeat_timeout_s: 0.1}", "watchdog.heartbeat_timeout_s: 0.1 is out of range, allowed [0.5, 600] seconds"},
      {"lcm: {jpeg_quality: 101}", "lcm.jpeg_quality: 101 is out of range, allowed 1 .. 100"},
      {"lcm: {channels: {status: \"\"}}", "lcm.channels.status: must have 1 to 255 characters"},
      {"lcm: {url: [a, b]}", "lcm.url: expected a string, got a list"},
      {"fingerprint: {workers: 0}", "fingerprint.workers: 0 is out of range, allowed 1 .. 64"},
      {"fingerprint: {edges: {mean_factor: 0}}", "fingerprint.edges.mean_factor: 0 is out of range, allowed (0, 100]"},
      {"fingerprint: {histogram: {achromatic_chroma: 1}}", "fingerprint.histogram.achromatic_chroma: 1 is out of range, allowed [0, 1)"},
      {"fingerprint: {histogram: {min_lightness: 0.6, max_lightness: 0.5}}", "fingerprint.histogram.max_lightness: 0.5 is out of range"},
      {"fingerprint: {keypoints: {backend: surf}}", "fingerprint.keypoints.backend: 'surf' is not allowed, expected one of: orb, sift, brisk, akaze"},
      {"fingerprint: {keypoints: {max_keypoints: 500, candidate_limit: 100}}", "fingerprint.keypoints.candidate_limit: 100 is out of range, allowed max_keypoints (500) .. 100000"},
      {"fingerprint: {keypoints: {max_keypoints: 1.5}}", "fingerprint.keypoints.max_keypoints: expected an integer in 0 .. 10000, got '1.5'"},
      {"similarity: {matcher: {max_hellinger_distance: 0}}", "similarity.matcher.max_hellinger_distance: 0 is out of range, allowed (0, 1]"},
      {"similarity: {histogram_weight: 2}", "similarity.histogram_weight: 2 is out of range, allowed [0, 1]"},
      {"segmentation: {window: 2}", "segmentation.window: 2 is out of range, allowed 3 .. 1000 frames"},
      {"segmentation: {valley: {gamma: 0.2, delta: 0.3}}", "segmentation.valley.delta: 0.3 is out of range, allowed [0, gamma = 0.2]"},
      {"segmentation: {window: 3, min_window_frames: 3, valley: {gamma: 1.6}}", "segmentation.valley.gamma: 1.6 is out of range, allowed [0, window / (window - 1) = 1.5]"},
      {"segmentation: {cut_placement: middle}", "segmentation.cut_placement: 'middle' is not allowed"},
      {"segmentation: {window_m: -1}", "segmentation.window_m: -1 is out of range, allowed [0, 1000] metres"},
      {"segmentation: {motion: {timeout_s: 0}}", "segmentation.motion.timeout_s: 0 is out of range, allowed (0, 3600] seconds"},
      {"segmentation: {motion: {standing_speed_mps: 11}}", "segmentation.motion.standing_speed_mps: 11 is out of range"},
      {"segmentation: {motion: {standing_turn_rate_rps: -1}}", "segmentation.motion.standing_turn_rate_rps: -1 is out of range"},
      {"segmentation: {motion: {stand: 1}}", "unknown key 'segmentation.motion.stand'"},
      {"topology: {particles: 0}", "topology.particles: 0 is out of range, allowed 1 .. 1000000"},
      {"topology: {particles: lots}", "topology.particles: expected an integer in 1 .. 1000000, got 'lots'"},
      {"topology: {particles: 010}", "topology.particles: '010' has a leading zero"},
      {"base: &b 5\ntopology: {particles: *b}", "line 2: aliases (*name) are not allowed"},
      {"topology: {new_node_probability: 1}", "topology.new_node_probability: 1 is out of range, allowed (0, 1)"},
      {"topology: {new_node_likelihood_floor: 1}", "topology.new_node_likelihood_floor: 1 is out of range, allowed [0, 1)"},
      {"topology: {max_successors: 9}", "topology.max_successors: 9 is out of range, allowed 1 .. 8"},
      {"topology: {seed: -1}", "topology.seed: -1 is out of range"},
      {"topology: {slice_items: 0}", "topology.slice_items: 0 is out of range, allowed 1 .. 1000000 work items"},
      {"topology: {alpha: .nan}", "topology.alpha: nan is out of range, allowed (0, 1e+06]"},
      {"pipeline: 3", "pipeline: expected a mapping of keys, got '3'"},
      {"map: {path: }", "map.path: has no value"},
      {"[1, 2]", "top level: expected a mapping of keys, got a list"},
      {"pipeline: {queues: {frames: 2", "test.yaml: not valid YAML"},
  };
  for (const auto& [yaml, expected] : cases) {
    GIVEN(yaml) {
      const std::string error = errorOf(yaml);
      THEN("the error names it: " + expected) {
        CHECK_THAT(error, Catch::Contains(expected));
        CHECK_THAT(error, Catch::StartsWith("test.yaml: "));
      }
    }
  }
}

SCENARIO("A config file that cannot be read is refused with its path") {
  CHECK_THROWS_WITH(loadDaemonConfig("/nonexistent/toposlam.yaml"),
                    Catch::Contains("cannot read the config file '/nonexistent/toposlam.yaml'"));
}

SCENARIO("A folder, an endless file, a repeated key or a second document is refused, not read as defaults") {
  CHECK_THROWS_WITH(loadDaemonConfig(TOPOSLAM_SOURCE_DIR "/config"),
                    Catch::Contains("is a folder") && Catch::Contains("config/toposlam.yaml"));
  CHECK_THROWS_WITH(loadDaemonConfig("/dev/zero"), Catch::Contains("'/dev/zero' is larger than 1024 KiB"));
  CHECK_THAT(errorOf("map:\n  path: a.tsm\n  path: b.tsm\n"),
             Catch::Contains("duplicate key 'map.path' (line 3)"));
  CHECK_THAT(errorOf("source: images:a\nsource: images:b\n"), Catch::Contains("duplicate key 'source' (line 2)"));
  CHECK_THAT(errorOf("source: images:a\n---\nsource: images:b\n"),
             Catch::Contains("holds 2 YAML documents") && Catch::StartsWith("test.yaml"));
  CHECK(errorOf("").empty());
  CHECK(errorOf("---\nsource: images:a\n").empty());
  CHECK(errorOf("source: images:a\n...\n").empty());
  // yaml-cpp 0.7's LoadAll loops forever on this (found by fuzz_config); YAML::Load returns at once.
  CHECK_NOTHROW(errorOf(",iQSLAM_MOar"));
  CHECK_THAT(errorOf("map:\n  max_mb: 0\n"), Catch::Contains("map.max_mb"));
  CHECK_THAT(errorOf("lcm:\n  url: udp-multicast-please\n"), Catch::Contains("lcm.url: 'udp-multicast-please' is not an LCM URL"));
  CHECK(errorOf("lcm:\n  url: memq://\n").empty());
}

SCENARIO("DaemonConfig::validate() names keys by their YAML path") {
  DaemonConfig c;
  CHECK(c.validate().empty());
  c.map.save_period_s = 0.5;
  CHECK_THAT(c.validate(), Catch::StartsWith("map.save_period_s: 0.5"));
  c = DaemonConfig{};
  c.watchdog.heartbeat_timeout_s = 0;
  CHECK_THAT(c.validate(), Catch::StartsWith("watchdog.heartbeat_timeout_s: "));
  c = DaemonConfig{};
  c.pipeline.queues.segmented = 0;
  CHECK_THAT(c.validate(), Catch::StartsWith("pipeline.queues.segmented: "));
  c = DaemonConfig{};
  c.topology.particles = 0;
  CHECK_THAT(c.validate(), Catch::StartsWith("topology."));
  c = DaemonConfig{};
  c.source.clear();
  CHECK_THAT(c.validate(), Catch::StartsWith("source: must not be empty"));
}

SCENARIO("GIVEN preset: thesis WHEN the config is read THEN every stage takes the published method and later keys override it") {
  const DaemonConfig c = parseDaemonConfig("preset: thesis\nsegmentation: {window: 40}\n");
  CHECK(c.preset == "thesis");
  CHECK(c.similarity.histogram_weight == 0.5);
  CHECK(c.similarity.keypoint_scoring == KeypointScoring::PossibleNgrams);
  CHECK_FALSE(c.similarity.matcher.mutual_check);
  CHECK(c.fingerprint.keypoints.orb_levels == 4);
  CHECK(c.segmentation.window_s == 0.0);
  CHECK(c.segmentation.window == 40);  // the key after the preset wins
  CHECK(c.segmentation.valley.delta == 0.25);
  CHECK(c.segmentation.cut_placement == CutPlacement::ValleyFrame);
  CHECK(c.topology.likelihood == LikelihoodModel::Absolute);
  CHECK(c.topology.new_node_probability == 0.05);
  CHECK(c.topology.new_node_likelihood_floor == 0.0);
  CHECK(c.topology.new_node_entropy);
  CHECK_FALSE(c.segmentation.doorway_borders);
  CHECK(c.segmentation.doorway_shift_s == 0.0);
  CHECK_FALSE(c.sequence_evidence.frame_revisits);  // no per-frame answer: not in the thesis
  CHECK(c.sequence_evidence.weight == 0.0);
  const DaemonConfig d = parseDaemonConfig("source: \"sim:office\"\n");
  CHECK(d.sequence_evidence.frame_revisits);
  CHECK(d.sequence_evidence.memory_s == 40.0);
  CHECK(d.sequence_evidence.loop.scales == 3);
  CHECK(d.sequence_evidence.min_score == 2.0);
  CHECK(d.sequence_evidence.weight == 0.0);  // no evidence in the filter by default (docs/results.md)
  CHECK(d.preset == "default");
  CHECK(d.topology.likelihood == LikelihoodModel::Relative);
  CHECK(d.segmentation.window_s == 6.0);
  CHECK(d.topology.new_node_probability == 0.02);
  CHECK(d.topology.new_node_likelihood_floor == 0.01);
  CHECK(d.segmentation.doorway_borders);
  CHECK_THROWS_WITH(parseDaemonConfig("preset: fancy\n"), Catch::Contains("preset") && Catch::Contains("thesis"));
}

SCENARIO("GIVEN a 1 KB YAML alias bomb WHEN the config is read THEN it is refused at once, naming the alias") {
  // Nine levels of ten aliases each: a billion leaves if expanded (issue 41: start-up hung for a minute).
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level < 9; ++level) {
    // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string.
    const std::string name = std::to_string(level);
    bomb.append("a").append(name).append(": &a").append(name).append(" [");
    for (int i = 0; i < 10; ++i) bomb.append(i ? ", *a" : "*a").append(std::to_string(level - 1));
    bomb += "]\n";
  }
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(parseDaemonConfig(bomb, "bomb.yaml"), Catch::Contains("bomb.yaml: line 2: aliases (*name) are not allowed"));
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(2));  // minutes before; about 1 ms now
}

SCENARIO("GIVEN the fuzz corpus's alias and octal-looking configs WHEN each is read THEN aliases are refused at once "
         "and numbers with a leading zero are refused") {
  // The checked-in seeds of fuzz_config (tests/fuzz/corpus/config, made by fuzz_make_seeds): this keeps them
  // meaningful, and fuzz_replay_config replays them (and every past finding) in every build.
  const std::string corpus = std::string(TOPOSLAM_SOURCE_DIR) + "/tests/fuzz/corpus/config/";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"alias_bomb", "alias_bomb: line 2: aliases (*name) are not allowed"},
      {"alias_nested", "alias_nested: line 2: aliases (*name) are not allowed"},
      {"alias_merge_key", "alias_merge_key: line 3: aliases (*name) are not allowed"},
      {"alias_merge_list", "alias_merge_list: line 4: aliases (*name) are not allowed"},
      {"alias_as_key", "alias_as_key: line 2: aliases (*name) are not allowed"},
      {"alias_undefined", "alias_undefined: not valid YAML"},
      {"alias_second_document", "alias_second_document: holds 2 YAML documents"},
      {"octal_leading_zero", "topology.particles: '010' has a leading zero"},
      {"octal_signed", "pipeline.queues.frames: '-010' has a leading zero"},
      {"octal_0o", "topology.particles: expected an integer"},
  };
  for (const auto& [name, expected] : refused) {
    WHEN(name + " is read") {
      const std::string text = fileText(corpus + name);
      REQUIRE_FALSE(text.empty());
      const auto start = std::chrono::steady_clock::now();
      std::string error;
      try {
        (void)parseDaemonConfig(text, name);
      } catch (const ConfigError& e) {
        error = e.what();
      }
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      THEN("it is refused: " + expected) {
        CHECK_THAT(error, Catch::Contains(expected));
        CHECK(ms < 1000.0);  // about 0.1 ms; the alias bomb took minutes before issue 41
      }
    }
  }
  WHEN("an anchor with no alias, a hexadecimal count and a real with a leading zero are read") {
    auto read = [&](const std::string& name) { return parseDaemonConfig(fileText(corpus + name), name); };
    THEN("they mean what both YAML versions agree on") {
      CHECK(read("anchor_only").topology.particles == 50);
      CHECK(read("hexadecimal").topology.particles == 16);
      CHECK(read("real_leading_zero").segmentation.window_s == 6.5);
    }
  }
}

SCENARIO("GIVEN a config file and command-line overrides WHEN the command line's config is made THEN the preset comes "
         "first, then the file, then the overrides in order, each refused by its key") {
  const std::string file = TOPOSLAM_BINARY_DIR "/command-line-config.yaml";
  {
    std::ofstream out(file);
    out << "preset: default\nsegmentation:\n  window_s: 4\ntopology:\n  particles: 200\n";
  }
  WHEN("the command line names the thesis preset and sets one key the file sets too") {
    const DaemonConfig c = commandLineConfig(
        file, {{"preset", "thesis", "--preset"}, parseSetOverride("topology.particles=300")});
    THEN("the thesis preset replaces the file's, the file's keys override it and --set overrides the file") {
      CHECK(c.preset == "thesis");
      CHECK(c.segmentation.window == 25);       // the thesis preset's
      CHECK(c.segmentation.window_s == 4.0);    // the file's, over the preset
      CHECK(c.topology.particles == 300);       // --set, over the file
      CHECK(c.topology.likelihood == LikelihoodModel::Absolute);
    }
  }
  WHEN("no file is given") {
    const DaemonConfig c = commandLineConfig("", {parseSetOverride("segmentation.window=40")});
    THEN("the built-in defaults take the override") {
      CHECK(c.preset == "default");
      CHECK(c.segmentation.window == 40);
      CHECK(c.segmentation.window_s == 6.0);
    }
  }
  WHEN("overrides are out of range, unknown, malformed or break a cross-key constraint") {
    const auto error = [&](const std::vector<std::string>& sets) -> std::string {
      try {
        std::vector<ConfigOverride> overrides;
        for (const std::string& set : sets) overrides.push_back(parseSetOverride(set));
        commandLineConfig("", overrides);
      } catch (const ConfigError& e) {
        return e.what();
      }
      return "";
    };
    THEN("each is refused naming the option as given and the key") {
      CHECK(error({"segmentation.window=2"}) ==
            "command line: --set segmentation.window=2: segmentation.window: 2 is out of range, allowed 3 .. 1000 frames");
      CHECK(error({"topology.particles=many"}) ==
            "command line: --set topology.particles=many: topology.particles: expected an integer in 1 .. 1000000, "
            "got 'many'");
      CHECK(error({"segmentation.windw=20"}).rfind("command line: --set segmentation.windw=20: unknown key "
                                                   "'segmentation.windw'", 0) == 0);
      CHECK(error({"segmentation=20"}).find("'segmentation' is a section") != std::string::npos);
      CHECK(error({"segmentation.window"}) ==
            "command line: --set segmentation.window: expected KEY=VALUE, e.g. --set segmentation.window_s=6");
      CHECK(error({"segmentation.window=4"}) ==
            "command line: segmentation.min_window_frames: 5 is out of range, allowed 3 .. window (4) frames");
      CHECK(error({"preset=paper"}).rfind("command line: --set preset=paper: preset: 'paper' is not allowed", 0) == 0);
    }
  }
}
