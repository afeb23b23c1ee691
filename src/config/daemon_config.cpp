// DaemonConfig: YAML -> stage config structs, with strict key and range checking; see the header.
#include "toposlam/config/daemon_config.hpp"

#include <vector>

#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/config_reader.hpp"
#include "toposlam/config/method_preset.hpp"

namespace toposlam {

void applyMethodPreset(const std::string& name, DaemonConfig& c) {
  const MethodPreset preset = methodPreset(name);
  c.preset = preset.name;
  c.fingerprint = preset.fingerprint;
  c.similarity = preset.similarity;
  c.segmentation = preset.segmentation;
  c.topology = preset.topology;
  c.sequence_evidence = preset.sequence_evidence;
}

DaemonConfig::DaemonConfig() {
  map.path = "map.tsm";
  applyMethodPreset(preset, *this);
}

std::string DaemonConfig::validate() const {
  if (std::string problem = configKeysProblem(daemonConfigKeys(), *this); !problem.empty()) return problem;
  // The stages' own checks, which the table's ranges should already cover (test_config_keys): a
  // problem found only here is reported as the stage words it.
  const std::pair<const char*, std::string> stages[] = {
      {"pipeline (PipelineConfig)", pipeline.validate()},
      {"map (MapConfig)", map.validate()},
      {"watchdog (WatchdogConfig)", watchdog.validate()},
      {"fingerprint (VpackConfig)", fingerprint.validate()},
      {"similarity (NgramSimilarityConfig)", similarity.validate()},
      {"segmentation (FiedlerSegmenterConfig)", segmentation.validate()},
      {"segmentation.motion (MotionGateConfig)", segmentation_stage.motion.validate()},
      {"topology (TopologyFilterConfig)", topology.validate()},
      {"topology.sequence_evidence (SequenceEvidenceConfig)", sequence_evidence.validate()},
  };
  for (const auto& [stage, problem] : stages)
    if (!problem.empty()) return std::string(stage) + ": " + problem;
  return "";
}

DaemonConfig parseDaemonConfig(const std::string& yaml_text, const std::string& origin, const std::string& preset) {
  DaemonConfig config;
  // The preset first, wherever it is written: it gives every stage's settings, the other keys override them.
  // The command line's preset, if any, in place of the text's.
  if (!preset.empty()) {
    try {
      setConfigValue(config, "preset", preset);
    } catch (const ConfigError& e) {
      throw ConfigError(origin + ": " + e.what());
    }
  }
  readConfigText(yaml_text, origin, daemonConfigKeys(), config, ConfigReadOrder{"preset", !preset.empty()});
  if (std::string problem = config.validate(); !problem.empty()) throw ConfigError(origin + ": " + problem);
  return config;
}

void setConfigValue(DaemonConfig& config, const std::string& path, const std::string& text) {
  const ConfigKey& key = daemonConfigKey(path);
  key.set(config, configValueFromText(key, text));
}

DaemonConfig loadDaemonConfig(const std::string& path, const std::string& preset) {
  return parseDaemonConfig(readConfigFile(path, "toposlam.yaml"), path, preset);
}

ConfigOverride parseSetOverride(const std::string& assignment) {
  return parseSetAssignment(configKeySpecs(daemonConfigKeys()), assignment, "segmentation.window_s=6",
                            "docs/config.md, or `toposlam config --print`");
}

DaemonConfig commandLineConfig(const std::string& path, const std::vector<ConfigOverride>& overrides) {
  std::string preset;
  for (const ConfigOverride& o : overrides)
    if (o.path == "preset") preset = o.text;
  if (!preset.empty()) {
    try {
      DaemonConfig probe;
      setConfigValue(probe, "preset", preset);  // an unknown name: said as the user wrote it
    } catch (const ConfigError& e) {
      for (const ConfigOverride& o : overrides)
        if (o.path == "preset" && o.text == preset) throw ConfigError("command line: " + o.given_as + ": " + e.what());
    }
  }
  DaemonConfig config;
  if (!path.empty()) {
    config = loadDaemonConfig(path, preset);
  } else if (!preset.empty()) {
    applyMethodPreset(preset, config);
  }
  for (const ConfigOverride& o : overrides) {
    if (o.path == "preset") continue;  // applied first
    try {
      setConfigValue(config, o.path, o.text);
    } catch (const ConfigError& e) {
      throw ConfigError("command line: " + o.given_as + ": " + e.what());
    }
  }
  if (std::string problem = config.validate(); !problem.empty()) throw ConfigError("command line: " + problem);
  return config;
}

}  // namespace toposlam
