// The config key table, checked mechanically key by key: its defaults are the code's, every key reads
// back what --print-config wrote, every range is enforced by the table itself (naming key, value, range
// and unit) and the checked-in config/toposlam.yaml and docs/config.md are what the table makes.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/config_text.hpp"
#include "toposlam/io/frame_recorder.hpp"
#include "toposlam/config/daemon_config.hpp"

using namespace toposlam;

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string errorOf(const std::string& yaml) {
  try {
    parseDaemonConfig(yaml, "test.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// Values of `key` other than its default, in the order they are tried.
std::vector<ConfigValue> otherValues(const ConfigKey& key) {
  std::vector<ConfigValue> values;
  switch (key.kind) {
    case ConfigKind::Integer:
      values = {key.integer_high, key.integer_low, (key.integer_low + key.integer_high) / 2};
      break;
    case ConfigKind::Real: {
      const double low = key.low_open ? std::nextafter(key.low, key.high) : key.low;
      const double high = key.high_open ? std::nextafter(key.high, key.low) : key.high;
      values = {high, low, (low + high) / 2, low + (high - low) / 7};
      break;
    }
    case ConfigKind::Flag:
      values = {!std::get<bool>(key.default_value)};
      break;
    case ConfigKind::Text:
      values = {std::string("udpm://x \"quoted\" \\ # not a comment").substr(0, key.max_length), std::string("tsl-x")};
      break;
    case ConfigKind::Choice:
      for (const std::string& c : key.choices) values.emplace_back(c);
      break;
  }
  std::vector<ConfigValue> others;
  for (const ConfigValue& v : values)
    if (v != key.default_value) others.push_back(v);
  return others;
}

// Every other value of `key` on the defaults, then on `second_base`.
std::vector<std::pair<DaemonConfig, ConfigValue>> candidates(const ConfigKey& key, const DaemonConfig& second_base) {
  std::vector<std::pair<DaemonConfig, ConfigValue>> out;
  for (const DaemonConfig& base : {DaemonConfig{}, second_base})
    for (const ConfigValue& value : otherValues(key))
      if (key.get(base) != value) out.emplace_back(base, value);
  return out;
}

// A value just outside the key's range, below or above; none when the range ends at the type's end.
std::vector<ConfigValue> outsideValues(const ConfigKey& key) {
  if (key.kind == ConfigKind::Integer) {
    std::vector<ConfigValue> v = {key.integer_low - 1};
    if (key.integer_high < std::numeric_limits<long long>::max()) v.emplace_back(key.integer_high + 1);
    return v;
  }
  if (key.kind == ConfigKind::Real) {
    const double inf = std::numeric_limits<double>::infinity();
    return {key.low_open ? key.low : std::nextafter(key.low, -inf),
            key.high_open ? key.high : std::nextafter(key.high, inf)};
  }
  return {};
}

}  // namespace

SCENARIO("GIVEN the key table WHEN a DaemonConfig is default-constructed THEN every key holds the table's default") {
  const DaemonConfig defaults;
  std::set<std::string> paths;
  for (const ConfigKey& key : daemonConfigKeys()) {
    INFO(key.path);
    CHECK(paths.insert(key.path).second);  // each key once
    CHECK(key.get(defaults) == key.default_value);
    CHECK(key.problem(key.default_value).empty());
    CHECK_FALSE(key.help.empty());
  }
  // Every section of the generated YAML has its comment.
  for (const ConfigKey& key : daemonConfigKeys())
    for (std::size_t dot = key.path.find('.'); dot != std::string::npos; dot = key.path.find('.', dot + 1)) {
      const std::string section = key.path.substr(0, dot);
      bool found = false;
      for (const ConfigSection& s : daemonConfigSections()) found = found || s.path == section;
      INFO(section);
      CHECK(found);
    }
  CHECK(daemonConfigKeys().size() == paths.size());
  CHECK(daemonConfigKeys().front().path == "preset");
  CHECK(defaults.validate().empty());
}

SCENARIO("GIVEN the stage structs as constructed WHEN compared with the key table THEN they hold its defaults, "
         "but for the keys the default preset writes") {
  DaemonConfig structs;
  static_cast<StageSettings&>(structs) = StageSettings{};  // every stage's struct as constructed, no preset
  std::set<std::string> differ;
  for (const ConfigKey& key : daemonConfigKeys())
    if (key.path != "preset" && key.get(structs) != key.default_value) differ.insert(key.path);
  // segmentation.window: one default (100), the table's; the struct's was 30 and the preset's 100.
  CHECK(differ.count("segmentation.window") == 0);
  CHECK(std::get<long long>(daemonConfigKey("segmentation.window").default_value) == FiedlerSegmenterConfig{}.window);
  // The rest: what the "default" preset (method_preset.cpp, similarity_preset.cpp) measured on real frames,
  // over the stage structs, which keep the thesis' (or neutral) values for the algorithms' own tests.
  CHECK(differ == std::set<std::string>{
                      "fingerprint.keypoints.orb_levels", "segmentation.doorway_borders", "segmentation.doorway_shift_s",
                      "segmentation.min_frame_spacing_m", "segmentation.min_frame_spacing_rad",
                      "segmentation.place_samples", "segmentation.place_views", "segmentation.window_s", "similarity.histogram_only_fallback",
                      "similarity.histogram_weight", "similarity.keypoint_scoring",
                      "similarity.matcher.max_angle_difference_deg", "similarity.matcher.mutual_check",
                      "similarity.matcher.ratio_test", "topology.gamma_scale", "topology.gamma_shape",
                      "topology.likelihood", "topology.new_node_entropy", "topology.new_node_likelihood_floor",
                      "topology.new_node_probability", "topology.relative_offset", "topology.relative_slope"});
}

SCENARIO("GIVEN the effective config printed as YAML WHEN it is read back THEN every key has its value again") {
  GIVEN("the defaults") {
    const std::string printed = configYaml(DaemonConfig{}, false);
    CHECK(configYaml(parseDaemonConfig(printed, "printed"), false) == printed);
    // The commented form reads back too.
    CHECK(configYaml(parseDaemonConfig(configYaml(DaemonConfig{}, true), "commented"), false) == printed);
  }
  GIVEN("each key set to another allowed value, one at a time") {
    for (const ConfigKey& key : daemonConfigKeys()) {
      INFO(key.path);
      bool exercised = false;
      // Threads' policy and priority change together: fifo needs a priority of 1 .. 99.
      DaemonConfig fifo;
      for (ThreadSettings* t : {&fifo.pipeline.threads.capture, &fifo.pipeline.threads.fingerprint,
                                &fifo.pipeline.threads.segmentation, &fifo.pipeline.threads.topology,
                                &fifo.pipeline.threads.publisher, &fifo.pipeline.threads.map_writer,
                                &fifo.pipeline.threads.lcm_receiver, &fifo.pipeline.threads.recorder}) {
        t->policy = SchedulingPolicy::Fifo;
        t->priority = 10;
      }
      for (const auto& [base, value] : candidates(key, fifo)) {
        DaemonConfig c = base;
        key.set(c, value);
        if (const std::size_t at = key.path.rfind(".policy"); at != std::string::npos && at + 7 == key.path.size())
          daemonConfigKey(key.path.substr(0, at) + ".priority").set(c, value == ConfigValue(std::string("fifo")) ? 10LL : 0LL);
        if (!c.validate().empty()) continue;  // a cross-key constraint refuses it with the others' defaults
        const std::string printed = configYaml(c, false);
        const DaemonConfig read = parseDaemonConfig(printed, "printed");
        CHECK(key.get(read) == value);
        CHECK(configYaml(read, false) == printed);
        exercised = true;
        break;
      }
      CHECK(exercised);
    }
  }
}

SCENARIO("GIVEN a number just outside a key's range WHEN validated or read THEN the table refuses it naming key, value and range") {
  for (const ConfigKey& key : daemonConfigKeys()) {
    for (const ConfigValue& value : outsideValues(key)) {
      const std::string text = key.yamlText(value);
      INFO(key.path << " = " << text);
      DaemonConfig c;
      key.set(c, value);
      const std::string problem = c.validate();
      // The table's check, not a stage's backstop, is what refuses it.
      CHECK_THAT(problem, Catch::StartsWith(key.path + ": ") && Catch::Contains("is out of range, allowed") &&
                              Catch::Contains(key.rangeText()));
      if (!key.unit.empty()) CHECK_THAT(problem, Catch::Contains(key.unit));
      // The same from YAML: the key written at its path.
      std::string yaml, indent;
      std::size_t begin = 0;
      for (std::size_t dot; (dot = key.path.find('.', begin)) != std::string::npos; begin = dot + 1) {
        yaml += indent + key.path.substr(begin, dot - begin) + ":\n";
        indent += "  ";
      }
      yaml += indent + key.path.substr(begin) + ": " + text + "\n";
      CHECK_THAT(errorOf(yaml), Catch::StartsWith("test.yaml: " + key.path + ": ") && Catch::Contains("out of range"));
    }
  }
}

SCENARIO("GIVEN a key's range ends WHEN the stage checks them THEN the stage accepts what the table accepts") {
  // An end may break a constraint between keys (window 3 and min_window_frames 5): then that constraint
  // of the table refuses it, never a stage's own validate() behind the table.
  const auto refusedByTable = [](const std::string& problem) {
    if (problem.empty()) return true;
    for (const ConfigKey& k : daemonConfigKeys())
      if (k.cross_check && problem.rfind(k.path + ": ", 0) == 0) return true;
    return false;
  };
  for (const ConfigKey& key : daemonConfigKeys()) {
    if (key.kind != ConfigKind::Integer && key.kind != ConfigKind::Real) continue;
    std::vector<ConfigValue> ends;
    if (key.kind == ConfigKind::Integer) ends = {key.integer_low, key.integer_high};
    if (key.kind == ConfigKind::Real)
      ends = {key.low_open ? std::nextafter(key.low, key.high) : key.low,
              key.high_open ? std::nextafter(key.high, key.low) : key.high};
    for (const ConfigValue& value : ends) {
      INFO(key.path << " = " << key.yamlText(value));
      DaemonConfig c;
      key.set(c, value);
      const std::string problem = c.validate();
      INFO(problem);
      CHECK(refusedByTable(problem));
    }
  }
}

SCENARIO("GIVEN the checked-in config and docs WHEN compared with what the key table makes THEN they are equal") {
  // Regenerate: toposlam config --shipped > config/toposlam.yaml; toposlam config --docs > docs/config.md
  CHECK(readFile(TOPOSLAM_SOURCE_DIR "/config/toposlam.yaml") == shippedConfigYaml());
  CHECK(readFile(TOPOSLAM_SOURCE_DIR "/docs/config.md") == configDocsMarkdown());
  const DaemonConfig shipped = loadDaemonConfig(TOPOSLAM_SOURCE_DIR "/config/toposlam.yaml");
  DaemonConfig expected;
  expected.source = kShippedSource;
  CHECK(configYaml(shipped, false) == configYaml(expected, false));
}

SCENARIO("GIVEN keys the code had but YAML could not set WHEN written THEN they are read") {
  const DaemonConfig c = parseDaemonConfig("segmentation: {similarity_floor: 0.1}\n");
  CHECK(c.segmentation.similarity_floor == 0.1);
  CHECK_THAT(errorOf("segmentation: {similarity_floor: 1}"),
             Catch::Contains("segmentation.similarity_floor: 1 is out of range, allowed [0, 1)"));
}

SCENARIO("GIVEN an unknown key WHEN read THEN the error names its path, line and the known keys beside it") {
  CHECK_THAT(errorOf("source: \"sim:office\"\npipeline:\n  queue: {frames: 2}\n"),
             Catch::Contains("unknown key 'pipeline.queue' (line 3; known keys under 'pipeline': filter_budget_ms, "
                             "opencv_threads, queues, status_period_s, threads, thumbnail_width)"));
  CHECK_THAT(errorOf("sourse: x\n"), Catch::Contains("unknown key 'sourse' (line 1; known keys: "));
}

SCENARIO("GIVEN a command-line value WHEN set by its key's path THEN it is read like the YAML value") {
  DaemonConfig c;
  setConfigValue(c, "map.save_period_s", "30");
  setConfigValue(c, "pipeline.queues.overflow", "block");
  setConfigValue(c, "map.load_at_start", "false");
  setConfigValue(c, "map.path", "");
  CHECK(c.map.save_period_s == 30.0);
  CHECK(c.pipeline.queues.overflow == QueueOverflow::Block);
  CHECK_FALSE(c.map.load_at_start);
  CHECK(c.map.path.empty());
  CHECK_THROWS_WITH(setConfigValue(c, "map.save_period_s", "soon"),
                    Catch::StartsWith("map.save_period_s: expected a number in [0, 86400] seconds"));
  CHECK_THROWS_WITH(setConfigValue(c, "topology.particles", "0"),
                    Catch::StartsWith("topology.particles: 0 is out of range, allowed 1 .. 1000000"));
  // Options exist exactly for the keys the table gives one.
  std::set<std::string> options;
  for (const ConfigKey& key : daemonConfigKeys())
    if (!key.option.empty()) options.insert(key.option);
  CHECK(options == std::set<std::string>{"--source", "--log-level", "--lcm-url", "--map", "--localize-only", "--no-map-load",
                                         "--resume-other-source", "--resume-other-settings", "--source-from-start",
                                         "--save-period", "--overflow", "--record"});
}

SCENARIO("GIVEN the daemon's recording and toposlam capture --record WHEN neither is configured THEN they record "
         "at one JPEG quality") {
  // Recorded frames must replay the way the live run saw them: the daemon's record.jpeg_quality (key table)
  // and the recorder's own default (capture --record) were 90 and 95.
  CHECK(std::get<long long>(daemonConfigKey("record.jpeg_quality").default_value) == FrameRecorderConfig{}.jpeg_quality);
  CHECK(DaemonConfig{}.record.jpeg_quality == FrameRecorderConfig{}.jpeg_quality);
  CHECK(std::get<std::string>(daemonConfigKey("record.format").default_value) == FrameRecorderConfig{}.format);
}
