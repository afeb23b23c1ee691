// Command-line options that set a config key's value take its default and bounds from the key table
// (toposlam/config/config_keys.hpp), so a window or particle count is bounded the same way everywhere.
#pragma once

#include <string_view>

#include <CLI/CLI.hpp>

#include "toposlam/config/config_keys.hpp"

namespace toposlam::cli {

/// The closed range [low, high] of the numeric key at `path`, as a CLI11 check.
inline CLI::Range keyRange(std::string_view path) {
  const ConfigKey& key = daemonConfigKey(path);
  if (key.kind == ConfigKind::Integer) return CLI::Range(key.integer_low, key.integer_high);
  return CLI::Range(key.low, key.high);
}

/// The default of the integer key at `path`.
inline int keyDefaultInt(std::string_view path) { return static_cast<int>(daemonConfigKey(path).defaultNumber()); }

}  // namespace toposlam::cli
