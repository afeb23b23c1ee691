// The one declarative table of toposlamd's config keys (src/config/config_keys.cpp): for every key its
// YAML path, where it lands in DaemonConfig (a stage's own struct where there is one), its default, its
// allowed values, unit and help, and the toposlamd option that overrides it, if any. Everything else is
// made from the table: the YAML reader and the validation (daemon_config.cpp), toposlamd's override
// options, `toposlamd --print-config`, the comments of the shipped config/toposlam.yaml and the key
// table of docs/config.md (config_text.hpp; a test keeps both files equal to what the table makes).
//
// The mechanism (ConfigKey, its builders, the reader) is config_key.hpp and config_reader.hpp, shared with
// toposlam-bridge's table. Adding a key: the member in its struct and one entry in makeKeys() (config_keys.cpp), e.g.
//   k.push_back(integer("pipeline.queues.frames", AT(pipeline.queues.frames), 2, 1, 1024, "frames", "capture -> fingerprint"));
// (append .withOption("--name") for a toposlamd option; a new section also needs its line in
// daemonConfigSections()), then regenerate config/toposlam.yaml and docs/config.md with
// `toposlam config --shipped` / `--docs` (test_config_keys fails until they match). Nothing else lists keys.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "toposlam/config/config_key.hpp"

namespace toposlam {

struct DaemonConfig;

/// A key of toposlamd's table (the mechanism: config_key.hpp).
using ConfigKey = BasicConfigKey<DaemonConfig>;

/// Every key, in the order of the shipped config. `preset` is first: it sets every stage's settings
/// before the other keys are read.
const std::vector<ConfigKey>& daemonConfigKeys();
const std::vector<ConfigSection>& daemonConfigSections();
/// The key at `path`; throws std::out_of_range naming the path if there is none.
const ConfigKey& daemonConfigKey(std::string_view path);

/// "path" -> value (as YAML text) of every key recorded_in_map, read from `config`: what a map records it
/// was made with.
std::map<std::string, std::string> mapDecisionSettings(const DaemonConfig& config);

}  // namespace toposlam
