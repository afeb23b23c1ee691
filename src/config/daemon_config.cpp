// DaemonConfig: YAML -> stage config structs, with strict key and range checking; see the header.
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/method_preset.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>
#include <yaml-cpp/yaml.h>

namespace toposlam {

namespace {

std::string describeNode(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

std::string lineOf(const YAML::Node& node) { return "line " + std::to_string(node.Mark().line + 1); }

std::string joinPath(const std::string& section, const std::string& key) {
  return section.empty() ? key : section + "." + key;
}

// `node` as a value of `key`'s kind; ConfigError "<path>: expected ..." if it is not one. Ranges are not
// checked here.
ConfigValue valueOf(const ConfigKey& key, const YAML::Node& node) {
  const std::string& path = key.path;
  switch (key.kind) {
    case ConfigKind::Integer:
      // YAML 1.1 (yaml-cpp) reads 010 as octal 8, YAML 1.2 as decimal 10: neither is said, so refused.
      if (node.IsScalar()) {
        const std::string& text = node.Scalar();
        const std::size_t digits = text.find_first_not_of("+-");
        if (digits != std::string::npos && text.size() > digits + 1 && text[digits] == '0' &&
            text.find_first_not_of("0123456789", digits) == std::string::npos)
          throw ConfigError(path + ": '" + text + "' has a leading zero (read as octal by some YAML readers, as "
                            "decimal by others); write it without");
      }
      try {
        return node.as<long long>();
      } catch (const YAML::Exception&) {
        throw ConfigError(path + ": expected an integer in " + key.rangeText() + ", got " + describeNode(node));
      }
    case ConfigKind::Real:
      try {
        return node.as<double>();
      } catch (const YAML::Exception&) {
        throw ConfigError(path + ": expected a number in " + key.rangeText() + ", got " + describeNode(node));
      }
    case ConfigKind::Flag:
      try {
        return node.as<bool>();
      } catch (const YAML::Exception&) {
        throw ConfigError(path + ": expected true or false, got " + describeNode(node));
      }
    case ConfigKind::Text:
      if (!node.IsScalar()) throw ConfigError(path + ": expected a string, got " + describeNode(node));
      return node.Scalar();
    case ConfigKind::Choice:
      if (!node.IsScalar())
        throw ConfigError(path + ": " + describeNode(node) + " is not allowed, expected " + key.rangeText());
      return node.Scalar();
  }
  throw ConfigError(path + ": unknown kind of key");
}

// Reads one key's value: refused when it has none, is of the wrong kind or out of range (checked before
// it is stored, so a too large integer is never narrowed into the member).
void readKey(const ConfigKey& key, const YAML::Node& node, DaemonConfig& config) {
  if (node.IsNull()) throw ConfigError(key.path + ": has no value (remove the key to keep the default)");
  if (node.IsMap()) throw ConfigError(key.path + ": expected a value, got a mapping");
  const ConfigValue value = valueOf(key, node);
  if (std::string problem = key.problem(value); !problem.empty()) throw ConfigError(key.path + ": " + problem);
  key.set(config, value);
}

// The key table seen as a tree: the keys and the sections (mappings) at each path.
struct KeyTree {
  std::map<std::string, const ConfigKey*> keys;            // full path -> key
  std::map<std::string, std::set<std::string>> children;  // section path ("" = top level) -> child names

  KeyTree() {
    for (const ConfigKey& key : daemonConfigKeys()) {
      keys[key.path] = &key;
      std::string section;
      std::size_t begin = 0;
      for (std::size_t dot = key.path.find('.'); ; dot = key.path.find('.', begin)) {
        const std::string name = key.path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin);
        children[section].insert(name);
        if (dot == std::string::npos) break;
        section = joinPath(section, name);
        begin = dot + 1;
      }
    }
  }
  bool isSection(const std::string& path) const { return children.count(path) > 0; }
};

const KeyTree& keyTree() {
  static const KeyTree tree;
  return tree;
}

// Reads the mapping at `section` ("" = the document): every entry must be a key of the table or a
// section holding some; anything else is refused with its path and line.
void readSection(const YAML::Node& node, const std::string& section, DaemonConfig& config) {
  if (!node.IsDefined() || node.IsNull()) return;
  if (!node.IsMap())
    throw ConfigError((section.empty() ? std::string("top level") : section) + ": expected a mapping of keys, got " +
                      describeNode(node));
  const KeyTree& tree = keyTree();
  for (const auto& entry : node) {
    const std::string name = entry.first.IsScalar() ? entry.first.Scalar() : describeNode(entry.first);
    const std::string path = joinPath(section, name);
    if (path == "preset") continue;  // read first, by readConfig
    if (auto key = tree.keys.find(path); key != tree.keys.end()) {
      readKey(*key->second, entry.second, config);
    } else if (tree.isSection(path)) {
      readSection(entry.second, path, config);
    } else {
      std::string known;
      for (const std::string& k : tree.children.at(section)) known += (known.empty() ? "" : ", ") + k;
      throw ConfigError("unknown key '" + path + "' (" + lineOf(entry.first) + "; known keys" +
                        (section.empty() ? "" : " under '" + section + "'") + ": " + known + ")");
    }
  }
}

void readConfig(const YAML::Node& root, DaemonConfig& c, const std::string& preset_override) {
  // The preset first, wherever it is written: it gives every stage's settings, the other keys override them.
  // The command line's preset, if any, in place of the text's.
  if (!preset_override.empty()) {
    readKey(daemonConfigKey("preset"), YAML::Node(preset_override), c);
  } else if (root.IsMap()) {
    const YAML::Node& map = root;  // const look-up: the non-const operator[] would insert the key
    if (const YAML::Node preset = map["preset"]; preset.IsDefined()) readKey(daemonConfigKey("preset"), preset, c);
  }
  readSection(root, "", c);
}

// Documents in a YAML text: a "---" line (marker alone or followed by a space) after content, or content
// after a "..." end line, starts another one. A leading "---" is the first document's optional marker.
int yamlDocumentCount(const std::string& text) {
  int documents = 0;
  bool content = false;  // the current document has a non-comment line
  bool ended = false;    // a "..." line closed it
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const bool start = line.rfind("---", 0) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    const bool end = line.rfind("...", 0) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    const std::size_t first = line.find_first_not_of(" \t");
    const bool blank = first == std::string::npos || line[first] == '#';
    if (start) {
      if (content || ended || documents == 0) ++documents;
      content = line.find_first_not_of(" \t", 3) != std::string::npos && line[line.find_first_not_of(" \t", 3)] != '#';
      ended = false;
    } else if (end) {
      ended = true;
    } else if (!blank) {
      if (ended || documents == 0) ++documents;
      ended = false;
      content = true;
    }
  }
  return documents;
}

// Aliases (*name) are refused before the document is built: a config needs none, and yaml-cpp expands
// them into shared nodes that a walk over the tree visits once per path, so a 1 KB "billion laughs" file
// took minutes (issue 41). yaml-cpp's event parser reports each alias without expanding anything.
class AliasRefuser final : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
    if (first_alias_line < 0) first_alias_line = mark.line + 1;  // noted, not thrown through yaml-cpp
  }
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
  int first_alias_line = -1;
};

void refuseAliases(const std::string& yaml_text) {
  std::istringstream in(yaml_text);
  YAML::Parser parser(in);
  AliasRefuser refuser;
  parser.HandleNextDocument(refuser);
  if (refuser.first_alias_line > 0)
    throw ConfigError("line " + std::to_string(refuser.first_alias_line) +
                      ": aliases (*name) are not allowed; write the value out");
}

// yaml-cpp keeps both entries of a repeated key and look-ups see only the first, so the second would be
// ignored silently: refused, naming the key and its line.
void refuseDuplicateKeys(const YAML::Node& node, const std::string& path) {
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) refuseDuplicateKeys(item, path);
    return;
  }
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    const std::string full = path.empty() ? key : path + "." + key;
    if (!seen.insert(key).second)
      throw ConfigError("duplicate key '" + full + "' (line " + std::to_string(entry.first.Mark().line + 1) +
                        "); give each key once");
    refuseDuplicateKeys(entry.second, full);
  }
}

}  // namespace

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
  const std::vector<ConfigKey>& keys = daemonConfigKeys();
  for (const ConfigKey& key : keys)
    if (std::string problem = key.problem(key.get(*this)); !problem.empty()) return key.path + ": " + problem;
  for (const ConfigKey& key : keys)
    if (key.cross_check)
      if (std::string problem = key.cross_check(*this); !problem.empty()) return key.path + ": " + problem;
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
  YAML::Node root;
  try {
    // A second document ("---") would be ignored silently by YAML::Load: refused instead. Found by
    // scanning the lines, not with YAML::LoadAll, which loops forever on some malformed input in
    // yaml-cpp 0.7 (found by fuzz_config; tests/fuzz/corpus/config/loadall-hang).
    if (const int documents = yamlDocumentCount(yaml_text); documents > 1)
      throw ConfigError(origin + ": holds " + std::to_string(documents) +
                        " YAML documents (a '---' line starts another); toposlamd reads exactly one");
    refuseAliases(yaml_text);
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ": not valid YAML: " + e.what());
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  try {
    refuseDuplicateKeys(root, "");
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  DaemonConfig config;
  try {
    readConfig(root, config, preset);
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  if (std::string problem = config.validate(); !problem.empty()) throw ConfigError(origin + ": " + problem);
  return config;
}

void setConfigValue(DaemonConfig& config, const std::string& path, const std::string& text) {
  const ConfigKey& key = daemonConfigKey(path);
  const ConfigValue value = valueOf(key, YAML::Node(text));
  if (std::string problem = key.problem(value); !problem.empty()) throw ConfigError(path + ": " + problem);
  key.set(config, value);
}

DaemonConfig loadDaemonConfig(const std::string& path, const std::string& preset) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw ConfigError("the config file '" + path + "' is a folder; give the YAML file in it (e.g. " +
                      (std::filesystem::path(path) / "toposlam.yaml").string() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError("cannot read the config file '" + path + "' (does it exist and is it readable?)");
  // Read at most the cap (+1 to notice more): /dev/zero or a runaway file never reads forever.
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw ConfigError("cannot read the config file '" + path + "'");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes)
    throw ConfigError("the config file '" + path + "' is larger than " + std::to_string(kMaxConfigBytes >> 10) +
                      " KiB; is it really a toposlam config?");
  return parseDaemonConfig(text, path, preset);
}

ConfigOverride parseSetOverride(const std::string& assignment) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0)
    throw ConfigError("command line: --set " + assignment + ": expected KEY=VALUE, e.g. --set segmentation.window_s=6");
  ConfigOverride o{assignment.substr(0, equals), assignment.substr(equals + 1), "--set " + assignment};
  if (!keyTree().keys.count(o.path)) {
    std::string hint;
    if (keyTree().isSection(o.path)) hint = " ('" + o.path + "' is a section; name one of its keys)";
    throw ConfigError("command line: --set " + assignment + ": unknown key '" + o.path + "'" + hint +
                      " (the keys: docs/config.md, or `toposlam config --print`)");
  }
  return o;
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
