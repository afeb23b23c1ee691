// The key-table mechanism shared by every program with a YAML config (toposlamd's table in config_keys.hpp,
// toposlam-bridge's in firmware-host/bridge/bridge_config.cpp): a key is its dotted YAML path, the member
// of the program's config struct it lands in (the same path), its default, allowed values, unit and help.
// The table is the one place these are written; config_reader.hpp reads YAML and command-line text
// against it and writes the effective config back as YAML.
//
// A table is built with ConfigKeyBuilders<Config>, e.g.
//   integer("link.baud", [](auto& c) -> auto& { return c.link.baud; }, 115200, 9600, 4000000, "baud", "...")
#pragma once

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace toposlam {

/// A bad configuration: what() names the key (full dotted path) and the allowed values.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ConfigKind { Integer, Real, Flag, Text, Choice };

/// A key's value, by kind: Integer long long, Real double, Flag bool, Text and Choice std::string.
using ConfigValue = std::variant<long long, double, bool, std::string>;

/// What a key is, whatever config struct it belongs to: path, kind, default and allowed values.
struct ConfigKeySpec {
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
  std::vector<std::string> choices;            ///< Choice: the allowed names
  std::size_t min_length = 0, max_length = 0;  ///< Text
  std::string example;                         ///< Text: said when an empty value is refused
  /// The program's option overriding the key ("" = none). A Flag's option sets `option_sets`.
  std::string option;
  bool option_sets = true;
  /// A Choice key whose option is a flag: the value the flag sets ("" = an option taking the value).
  std::string option_value;
  /// toposlamd's table: true when the key changes what the mapping decides (which frames count, how they
  /// are fingerprinted, compared, segmented, how the filter weighs them): a map records its value, and a
  /// run with another value is refused the map unless map.resume_other_settings (mapDecisionSettings,
  /// docs/daemon.md).
  bool recorded_in_map = false;

  /// "1 .. 1024 frames", "[0, 3600] seconds (0 = off)", "one of: a, b", "1 to 255 characters".
  std::string rangeText() const;
  /// "" when `value` is allowed, else the problem without the path ("0 is out of range, allowed ...").
  std::string problem(const ConfigValue& value) const;
  /// `value` as YAML text that reads back to the same value (strings quoted, reals shortest exact).
  std::string yamlText(const ConfigValue& value) const;
  /// The integer or real default (for command-line defaults); throws std::logic_error for other kinds.
  double defaultNumber() const;
};

/// A number as range ends are written in messages and docs: the stream's default format ("0.1", "1e+06").
std::string configRangeNumber(double value);

/// A key of the table of `Config`: its spec, how its member is read and written, and any constraint
/// involving other keys.
template <typename Config>
struct BasicConfigKey : ConfigKeySpec {
  /// A constraint involving other keys: "" or the problem without the key's path (e.g. "0.3 is out of
  /// range, allowed [0, gamma = 0.2]"). Checked after every key's own range.
  std::function<std::string(const Config&)> cross_check;
  /// Reads / writes the key's member of `Config`.
  std::function<ConfigValue(const Config&)> get;
  std::function<void(Config&, const ConfigValue&)> set;

  // Table-building helpers (chainable).
  BasicConfigKey& withNote(std::string text) {
    note = std::move(text);
    return *this;
  }
  BasicConfigKey& withOption(std::string name, bool sets = true) {
    option = std::move(name);
    option_sets = sets;
    return *this;
  }
  /// A flag option that sets this choice key to `value` (`--localize-only` sets map.mode to localize).
  BasicConfigKey& withFlagOption(std::string name, std::string value) {
    option = std::move(name);
    option_value = std::move(value);
    return *this;
  }
  BasicConfigKey& withCrossCheck(std::function<std::string(const Config&)> check) {
    cross_check = std::move(check);
    return *this;
  }
  BasicConfigKey& exclusive(bool low_end, bool high_end) {
    low_open = low_end;
    high_open = high_end;
    return *this;
  }
};

/// A section (YAML mapping) of a config, with its comment in the generated YAML and docs.
struct ConfigSection {
  std::string path;  ///< "pipeline.queues"
  std::string help;
};

/// The makers of a table's entries. `access` is a callable returning the member by reference for a const
/// and a non-const Config alike: `[](auto& c) -> auto& { return c.link.baud; }`.
template <typename Config>
struct ConfigKeyBuilders {
  using Key = BasicConfigKey<Config>;

  static Key base(std::string path, ConfigKind kind, std::string unit, std::string help) {
    Key k;
    k.path = std::move(path);
    k.kind = kind;
    k.unit = std::move(unit);
    k.help = std::move(help);
    return k;
  }

  template <typename Access>
  static Key integer(std::string path, Access access, long long def, long long lo, long long hi,
                     std::string unit, std::string help) {
    Key k = base(std::move(path), ConfigKind::Integer, std::move(unit), std::move(help));
    k.default_value = def;
    k.integer_low = lo;
    k.integer_high = hi;
    k.low = static_cast<double>(lo);
    k.high = static_cast<double>(hi);
    k.get = [access](const Config& c) -> ConfigValue { return static_cast<long long>(access(c)); };
    k.set = [access](Config& c, const ConfigValue& v) {
      auto& member = access(c);
      member = static_cast<std::remove_reference_t<decltype(member)>>(std::get<long long>(v));
    };
    return k;
  }

  template <typename Access>
  static Key real(std::string path, Access access, double def, double lo, double hi, std::string unit,
                  std::string help) {
    Key k = base(std::move(path), ConfigKind::Real, std::move(unit), std::move(help));
    k.default_value = def;
    k.low = lo;
    k.high = hi;
    k.get = [access](const Config& c) -> ConfigValue { return static_cast<double>(access(c)); };
    k.set = [access](Config& c, const ConfigValue& v) { access(c) = std::get<double>(v); };
    return k;
  }

  template <typename Access>
  static Key flag(std::string path, Access access, bool def, std::string help) {
    Key k = base(std::move(path), ConfigKind::Flag, "", std::move(help));
    k.default_value = def;
    k.get = [access](const Config& c) -> ConfigValue { return static_cast<bool>(access(c)); };
    k.set = [access](Config& c, const ConfigValue& v) { access(c) = std::get<bool>(v); };
    return k;
  }

  /// A string of min_length .. max_length characters.
  template <typename Access>
  static Key text(std::string path, Access access, std::string def, std::size_t min_length,
                  std::size_t max_length, std::string help) {
    Key k = base(std::move(path), ConfigKind::Text, "", std::move(help));
    k.default_value = std::move(def);
    k.min_length = min_length;
    k.max_length = max_length;
    k.get = [access](const Config& c) -> ConfigValue { return std::string(access(c)); };
    k.set = [access](Config& c, const ConfigValue& v) { access(c) = std::get<std::string>(v); };
    return k;
  }

  /// One of `names`, each naming a value of the member (an enum or a string).
  template <typename Access, typename Value>
  static Key choice(std::string path, Access access, Value def,
                    std::vector<std::pair<std::string, Value>> names, std::string help) {
    Key k = base(std::move(path), ConfigKind::Choice, "", std::move(help));
    for (const auto& [name, value] : names) {
      k.choices.push_back(name);
      if (value == def) k.default_value = name;
    }
    k.get = [access, names](const Config& c) -> ConfigValue {
      for (const auto& [name, value] : names)
        if (value == access(c)) return name;
      return std::string("?");  // a value outside the table: problem() refuses it
    };
    k.set = [access, names](Config& c, const ConfigValue& v) {
      for (const auto& [name, value] : names)
        if (name == std::get<std::string>(v)) access(c) = value;
    };
    return k;
  }

  template <typename Access>
  static Key choice(std::string path, Access access, const std::string& def,
                    const std::vector<std::string>& names, std::string help) {
    std::vector<std::pair<std::string, std::string>> pairs;
    for (const std::string& n : names) pairs.emplace_back(n, n);
    return choice(std::move(path), access, def, pairs, std::move(help));
  }
};

/// The first problem of `config` against `keys`: a value out of its key's range, then a cross-key
/// constraint; "<path>: <problem>", or "" when there is none.
template <typename Config>
std::string configKeysProblem(const std::vector<BasicConfigKey<Config>>& keys, const Config& config) {
  for (const auto& key : keys)
    if (std::string problem = key.problem(key.get(config)); !problem.empty())
      return key.path + ": " + problem;
  for (const auto& key : keys)
    if (key.cross_check)
      if (std::string problem = key.cross_check(config); !problem.empty()) return key.path + ": " + problem;
  return "";
}

}  // namespace toposlam
