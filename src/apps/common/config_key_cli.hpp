// The options a program makes from its config key table (toposlam/config/config_key.hpp), toposlamd's and
// toposlam-bridge's alike: one per key that names an option (ConfigKeySpec::option), its help the key's
// help and allowed values. A flag sets its key to the table's value; any other option takes the key's
// value as written in the YAML. What was given becomes ConfigOverrides, applied after the file.
// Header only (CLI11 and the table's templates), so toposlam-bridge includes it without linking
// toposlam_app_common.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "toposlam/config/config_key.hpp"
#include "toposlam/config/config_reader.hpp"

namespace toposlam::cli {

template <typename Config>
class ConfigKeyOptions {
 public:
  /// Adds the options of `keys` to `app`; `keys` must outlive this.
  ConfigKeyOptions(CLI::App& app, const std::vector<BasicConfigKey<Config>>& keys) {
    for (const BasicConfigKey<Config>& key : keys) {
      if (key.option.empty()) continue;
      auto entry = std::make_unique<Entry>(Entry{&key, nullptr, {}});
      if (key.kind == ConfigKind::Flag || !key.option_value.empty()) {
        entry->text = !key.option_value.empty() ? key.option_value : key.option_sets ? "true" : "false";
        const std::string help = "set `" + key.path + "` to " + entry->text + " (" + key.help + ")";
        entry->option = app.add_flag(key.option, help);
      } else {
        entry->option =
            app.add_option(key.option, entry->text,
                           "override `" + key.path + "`: " + key.help + " (" + key.rangeText() + ")");
        if (key.kind == ConfigKind::Choice) entry->option->check(CLI::IsMember(key.choices));
        if (key.kind == ConfigKind::Integer) entry->option->type_name("INT");
        if (key.kind == ConfigKind::Real) entry->option->type_name("NUMBER");
      }
      entries_.push_back(std::move(entry));
    }
  }

  /// The value given for the key at `path` (as text), or nullptr when its option was not given.
  const std::string* given(const std::string& path) const {
    for (const auto& e : entries_)
      if (e->key->path == path && e->option->count() > 0) return &e->text;
    return nullptr;
  }

  /// Every option given, in the table's order, as overrides of their keys.
  std::vector<ConfigOverride> overrides() const {
    std::vector<ConfigOverride> out;
    for (const auto& e : entries_)
      if (e->option->count() > 0) out.push_back({e->key->path, e->text, e->key->option});
    return out;
  }

 private:
  struct Entry {
    const BasicConfigKey<Config>* key;
    CLI::Option* option;
    std::string text;  // CLI11 writes the option's value here (stable: the Entry is on the heap)
  };
  std::vector<std::unique_ptr<Entry>> entries_;
};

}  // namespace toposlam::cli
