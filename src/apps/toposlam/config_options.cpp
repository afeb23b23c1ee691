// The offline commands' configuration options; see config_options.hpp.
#include "config_options.hpp"

#include "toposlam/config/config_keys.hpp"

namespace toposlam::cli {

void addConfigOptions(CLI::App& command, ConfigOptions& options) {
  command.add_option("-c,--config", options.file,
                     "Config file: the YAML toposlamd reads (config/toposlam.yaml, docs/config.md); default: the "
                     "built-in defaults");
  command.add_option("--set", options.sets,
                     "Set a key of the config: --set KEY=VALUE (repeatable; keys and values as in the YAML, "
                     "docs/config.md), applied after the file and the options")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  addKeyAlias(command, options, "--preset", "preset");
}

void addKeyAlias(CLI::App& command, ConfigOptions& options, const std::string& name, const std::string& key) {
  const ConfigKey& k = daemonConfigKey(key);
  addKeyAlias(command, options, name, {key}, {}, "= --set " + key + "=VALUE: " + k.help + " (" + k.rangeText() + ")");
  const char* type = k.kind == ConfigKind::Integer ? "INT"
                     : k.kind == ConfigKind::Real  ? "NUMBER"
                     : k.kind == ConfigKind::Flag  ? "BOOL"
                                                   : "TEXT";
  options.aliases.back()->option->type_name(type);
}

void addKeyAlias(CLI::App& command, ConfigOptions& options, const std::string& name, std::vector<std::string> keys,
                 std::vector<std::pair<std::string, std::string>> values, const std::string& help) {
  auto alias = std::make_unique<ConfigAlias>();
  alias->name = name;
  alias->keys = std::move(keys);
  alias->values = std::move(values);
  alias->option = command.add_option(name, alias->text, help);
  if (!alias->values.empty()) {
    std::vector<std::string> allowed;
    for (const auto& [given, value] : alias->values) allowed.push_back(given);
    alias->option->check(CLI::IsMember(allowed));
  } else {
    alias->option->type_name("N");
  }
  options.aliases.push_back(std::move(alias));
}

void addFlagAlias(CLI::App& command, ConfigOptions& options, const std::string& name, const std::string& key_value,
                  const std::string& help) {
  auto alias = std::make_unique<ConfigAlias>();
  alias->name = name;
  alias->keys = {key_value};
  alias->option = command.add_flag(name, help);
  options.aliases.push_back(std::move(alias));
}

bool keyGiven(const ConfigOptions& options, const std::string& key) {
  for (const auto& alias : options.aliases) {
    if (alias->option->count() == 0) continue;
    for (const std::string& k : alias->keys)
      if (k.substr(0, k.find('=')) == key) return true;
  }
  for (const std::string& set : options.sets)
    if (set.substr(0, set.find('=')) == key) return true;
  return false;
}

DaemonConfig commandConfig(const ConfigOptions& options) {
  std::vector<ConfigOverride> overrides;
  for (const auto& alias : options.aliases) {
    if (alias->option->count() == 0) continue;
    std::string text = alias->text;
    for (const auto& [given, value] : alias->values)
      if (given == text) text = value;
    for (const std::string& key : alias->keys) {
      const std::size_t equals = key.find('=');
      if (equals == std::string::npos)
        overrides.push_back({key, text, alias->name});
      else
        overrides.push_back({key.substr(0, equals), key.substr(equals + 1), alias->name});
    }
  }
  for (const std::string& set : options.sets) overrides.push_back(parseSetOverride(set));
  return commandLineConfig(options.file, overrides);
}

}  // namespace toposlam::cli
