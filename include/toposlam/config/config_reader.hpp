// Reading and writing a config against its key table (config_key.hpp), for any program's table: the YAML
// file (one document, one mapping; unknown or repeated keys, aliases, values of the wrong kind or out of
// range refused with the key's full dotted path), one key's value as written on a command line, and the
// effective config as YAML (`--print-config`, the shipped file with every key's help as its comment).
// The functions taking ConfigKeySpec pointers do the work once for every table; the templates below adapt
// a table of BasicConfigKey<Config> to them.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "toposlam/config/config_key.hpp"

namespace toposlam {

/// A config file larger than this is refused (bytes).
inline constexpr std::size_t kMaxConfigBytes = 1 << 20;

/// A key read before all others, wherever it is written (toposlamd's `preset`, which sets the other keys'
/// defaults); `skip_first`: the text's own value of it is ignored (the command line gave it).
struct ConfigReadOrder {
  std::string first;
  bool skip_first = false;
};

/// Reads YAML `text` against `keys`: calls set(i, value) for every key keys[i] the text gives, its value of
/// the key's kind and in its range. ConfigError "<origin>: <problem>" for more than one document, an alias,
/// a repeated or unknown key (with its line and the known keys of its section), a value of the wrong kind
/// or out of range.
void readConfigYaml(const std::string& text, const std::string& origin,
                    const std::vector<const ConfigKeySpec*>& keys,
                    const std::function<void(std::size_t, const ConfigValue&)>& set,
                    const ConfigReadOrder& order = {});

/// The text of the config file at `path`: ConfigError if it cannot be read, is a folder (naming
/// `file_name`, the file expected in it) or is over kMaxConfigBytes.
std::string readConfigFile(const std::string& path, const std::string& file_name);

/// `text`, as written on a command line or in YAML, as a value of `key`: ConfigError "<path>: <problem>"
/// when it is not a value of the key's kind or is out of its range.
ConfigValue configValueFromText(const ConfigKeySpec& key, const std::string& text);

/// Every key of `keys` as YAML, in the table's order, sections as nested mappings; value_text(i) is keys[i]'s
/// value. With `comment` (not null), each key is preceded by comment(i) (a text repeated for a key of the
/// same name in sibling sections is said once) and each section by section_help(path) when not "".
std::string configYamlText(const std::vector<const ConfigKeySpec*>& keys,
                           const std::function<std::string(std::size_t)>& value_text,
                           const std::function<std::string(std::size_t)>& comment,
                           const std::function<std::string(const std::string&)>& section_help);

/// `text` as comment lines starting with `prefix` ("  # "), broken between words before 110 columns.
std::string configCommentLines(const std::string& prefix, const std::string& text);

/// A key's usual comment: its help and, but for a flag, its allowed values.
std::string configKeyComment(const ConfigKeySpec& key);

/// True when `path` is a section (holds keys) of `keys`.
bool isConfigSection(const std::vector<const ConfigKeySpec*>& keys, const std::string& path);

/// One key set on a command line: the key's path, its value as text, and how the user wrote it for
/// messages ("--set segmentation.window_s=6", "--window-s").
struct ConfigOverride {
  std::string path;
  std::string text;
  std::string given_as;
};

/// The override of `--set KEY=VALUE` (`assignment` is "KEY=VALUE") against `keys`; ConfigError "command
/// line: --set TEXT: ..." when it has no '=' (`example` is a correct one) or KEY is no key of the table
/// (`keys_listed` says where the keys are listed, e.g. "docs/config.md").
ConfigOverride parseSetAssignment(const std::vector<const ConfigKeySpec*>& keys,
                                  const std::string& assignment, const std::string& example,
                                  const std::string& keys_listed);

// --- A table of BasicConfigKey<Config>. ---

template <typename Config>
std::vector<const ConfigKeySpec*> configKeySpecs(const std::vector<BasicConfigKey<Config>>& keys) {
  std::vector<const ConfigKeySpec*> specs;
  specs.reserve(keys.size());
  for (const auto& key : keys) specs.push_back(&key);
  return specs;
}

/// Reads YAML `text` onto `config` (readConfigYaml); ranges are checked, cross-key constraints are not
/// (configKeysProblem).
template <typename Config>
void readConfigText(const std::string& text, const std::string& origin,
                    const std::vector<BasicConfigKey<Config>>& keys, Config& config,
                    const ConfigReadOrder& order = {}) {
  readConfigYaml(
      text, origin, configKeySpecs(keys),
      [&](std::size_t i, const ConfigValue& value) { keys[i].set(config, value); }, order);
}

/// Sets the key at `path` of `keys` from its text; ConfigError naming the key for a bad value, or "unknown
/// key" for a path that is no key.
template <typename Config>
void setConfigKey(const std::vector<BasicConfigKey<Config>>& keys, Config& config, const std::string& path,
                  const std::string& text) {
  for (const auto& key : keys)
    if (key.path == path) {
      key.set(config, configValueFromText(key, text));
      return;
    }
  throw ConfigError("unknown key '" + path + "'");
}

/// `config` as YAML with every key of `keys`; with `comments`, each key's configKeyComment and each
/// section's help from `sections`.
template <typename Config>
std::string configKeysYaml(const std::vector<BasicConfigKey<Config>>& keys,
                           const std::vector<ConfigSection>& sections, const Config& config, bool comments) {
  std::function<std::string(std::size_t)> comment;
  if (comments) comment = [&](std::size_t i) { return configKeyComment(keys[i]); };
  return configYamlText(
      configKeySpecs(keys), [&](std::size_t i) { return keys[i].yamlText(keys[i].get(config)); }, comment,
      [&](const std::string& path) {
        for (const ConfigSection& s : sections)
          if (s.path == path) return s.help;
        return std::string();
      });
}

}  // namespace toposlam
