// The one declarative table of toposlamd's config keys (src/config/config_keys.cpp): for every key its
// YAML path, where it lands in DaemonConfig (a stage's own struct where there is one), its default, its
// allowed values, unit and help, and the toposlamd option that overrides it, if any. Everything else is
// made from the table: the YAML reader and the validation (daemon_config.cpp), toposlamd's override
// options, `toposlamd --print-config`, the comments of the shipped config/toposlam.yaml and the key
// table of docs/config.md (config_text.hpp; a test keeps both files equal to what the table makes).
//
// Adding a key: the member in its struct and one entry in makeKeys() (config_keys.cpp), e.g.
//   k.push_back(integer("pipeline.queues.frames", AT(pipeline.queues.frames), 2, 1, 1024, "frames", "capture -> fingerprint"));
// (append .withOption("--name") for a toposlamd option; a new section also needs its line in
// daemonConfigSections()), then regenerate config/toposlam.yaml and docs/config.md with
// `toposlam config --shipped` / `--docs` (test_config_keys fails until they match). Nothing else lists keys.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace toposlam {

struct DaemonConfig;

enum class ConfigKind { Integer, Real, Flag, Text, Choice };

/// A key's value, by kind: Integer long long, Real double, Flag bool, Text and Choice std::string.
using ConfigValue = std::variant<long long, double, bool, std::string>;

struct ConfigKey {
  std::string path;  ///< dotted YAML path, e.g. "segmentation.window"
  ConfigKind kind = ConfigKind::Real;
  std::string unit;  ///< "seconds", "frames", ... ("" for plain numbers)
  std::string note;  ///< said after the range, e.g. "0 = off"
  std::string help;  ///< one or a few sentences: what the value does
  ConfigValue default_value;
  // Allowed values. Integer: [integer_low, integer_high]. Real: [low, high], an end excluded when *_open.
  long long integer_low = 0, integer_high = 0;
  double low = 0.0, high = 0.0;
  bool low_open = false, high_open = false;
  std::vector<std::string> choices;  ///< Choice: the allowed names
  std::size_t min_length = 0, max_length = 0;  ///< Text
  std::string example;  ///< Text: said when an empty value is refused
  /// The toposlamd option overriding the key ("" = none). A Flag's option sets `option_sets`.
  std::string option;
  bool option_sets = true;
  /// A Choice key whose option is a flag: the value the flag sets ("" = an option taking the value).
  std::string option_value;
  /// A constraint involving other keys: "" or the problem without the key's path (e.g. "0.3 is out of
  /// range, allowed [0, gamma = 0.2]"). Checked after every key's own range.
  std::function<std::string(const DaemonConfig&)> cross_check;
  /// True when the key changes what the mapping decides (which frames count, how they are fingerprinted,
  /// compared, segmented, how the filter weighs them): a map records its value, and a run with another
  /// value is refused the map unless map.resume_other_settings (mapDecisionSettings, docs/daemon.md).
  bool recorded_in_map = false;
  /// Reads / writes the key's member of DaemonConfig.
  std::function<ConfigValue(const DaemonConfig&)> get;
  std::function<void(DaemonConfig&, const ConfigValue&)> set;

  /// "1 .. 1024 frames", "[0, 3600] seconds (0 = off)", "one of: a, b", "1 to 255 characters".
  std::string rangeText() const;
  /// "" when `value` is allowed, else the problem without the path ("0 is out of range, allowed ...").
  std::string problem(const ConfigValue& value) const;
  /// `value` as YAML text that reads back to the same value (strings quoted, reals shortest exact).
  std::string yamlText(const ConfigValue& value) const;
  /// The integer or real default (for command-line defaults); throws std::logic_error for other kinds.
  double defaultNumber() const;

  // Table-building helpers (chainable).
  ConfigKey& withNote(std::string text) { note = std::move(text); return *this; }
  ConfigKey& withOption(std::string name, bool sets = true) { option = std::move(name); option_sets = sets; return *this; }
  /// A flag option that sets this choice key to `value` (`--localize-only` sets map.mode to localize).
  ConfigKey& withFlagOption(std::string name, std::string value) {
    option = std::move(name);
    option_value = std::move(value);
    return *this;
  }
  ConfigKey& withCrossCheck(std::function<std::string(const DaemonConfig&)> check) { cross_check = std::move(check); return *this; }
  ConfigKey& exclusive(bool low_end, bool high_end) { low_open = low_end; high_open = high_end; return *this; }
};

/// A section (YAML mapping) of the config, with its comment in the generated YAML and docs.
struct ConfigSection {
  std::string path;  ///< "pipeline.queues"
  std::string help;
};

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
