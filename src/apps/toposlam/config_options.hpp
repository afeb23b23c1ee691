// The configuration of the offline commands that run stages (`map`, `segment`): toposlamd's own, read the
// same way (daemon_config.hpp, commandLineConfig). `-c FILE` reads the YAML toposlamd reads, `--set
// KEY=VALUE` sets any key of the key table (config_keys.hpp), with the daemon's validation and messages.
// The older option spellings (`--window-s 6`, `--particles 500`, ...) are aliases: each one line naming the
// key it sets, with no default or range of its own (the key table's apply).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "toposlam/config/daemon_config.hpp"

namespace toposlam::cli {

/// One alias option: what it sets. `keys` are the keys it sets to its value (a key given as "KEY=VALUE"
/// is set to that fixed value instead); `values`, if any, translate the option's value first ("sequence"
/// -> "true").
struct ConfigAlias {
  std::string name;
  std::vector<std::string> keys;
  std::vector<std::pair<std::string, std::string>> values;
  std::string text;  ///< the option's value as given
  CLI::Option* option = nullptr;
};

struct ConfigOptions {
  std::string file;               ///< -c: the YAML file ("" = the built-in defaults)
  std::vector<std::string> sets;  ///< --set KEY=VALUE, in order
  std::vector<std::unique_ptr<ConfigAlias>> aliases;
};

/// -c/--config, --set and --preset (the alias of `preset`).
void addConfigOptions(CLI::App& command, ConfigOptions& options);
/// An alias `name` of the key `key` (its help, range and unit from the key table).
void addKeyAlias(CLI::App& command, ConfigOptions& options, const std::string& name, const std::string& key);
/// An alias setting several keys, or translating its values (see ConfigAlias), with its own help.
void addKeyAlias(CLI::App& command, ConfigOptions& options, const std::string& name, std::vector<std::string> keys,
                 std::vector<std::pair<std::string, std::string>> values, const std::string& help);

/// A flag alias setting one key to a fixed value (`key_value` is "KEY=VALUE").
void addFlagAlias(CLI::App& command, ConfigOptions& options, const std::string& name, const std::string& key_value,
                  const std::string& help);

/// True when the command line sets `key` (by an alias or --set).
bool keyGiven(const ConfigOptions& options, const std::string& key);

/// The config the command line gives: the file, then the aliases given, then --set, validated
/// (commandLineConfig). Throws ConfigError "command line: ..." or "<file>: ..." naming the key.
DaemonConfig commandConfig(const ConfigOptions& options);

}  // namespace toposlam::cli
