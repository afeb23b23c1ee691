// Texts made from the config key table: see config_text.hpp.
#include "toposlam/config/config_text.hpp"

#include <functional>
#include <vector>

#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/config_reader.hpp"
#include "toposlam/config/daemon_config.hpp"

namespace toposlam {

namespace {

std::string sectionHelp(const std::string& path) {
  for (const ConfigSection& s : daemonConfigSections())
    if (s.path == path) return s.help;
  return "";
}

DaemonConfig thesisConfig() {
  DaemonConfig thesis;
  applyMethodPreset("thesis", thesis);
  return thesis;
}

// A key's comment: its help, its allowed values and the thesis preset's value where it differs.
std::string keyComment(const ConfigKey& key, const DaemonConfig& thesis) {
  std::string comment = configKeyComment(key);
  const ConfigValue thesis_value = key.get(thesis);
  if (key.path != "preset" && thesis_value != key.default_value)
    comment += "; thesis preset " + key.yamlText(thesis_value);
  return comment;
}

}  // namespace

std::string configYaml(const DaemonConfig& config, bool comments) {
  const DaemonConfig thesis = thesisConfig();
  const std::vector<ConfigKey>& keys = daemonConfigKeys();
  std::function<std::string(std::size_t)> comment;
  if (comments) comment = [&](std::size_t i) { return keyComment(keys[i], thesis); };
  return configYamlText(
      configKeySpecs(keys), [&](std::size_t i) { return keys[i].yamlText(keys[i].get(config)); }, comment, sectionHelp);
}

std::string shippedConfigYaml() {
  DaemonConfig shipped;
  shipped.source = kShippedSource;
  return "# toposlam.yaml: the one config of toposlamd (installed as /etc/toposlam/toposlam.yaml; with systemd,\n"
         "# ConfigurationDirectory=toposlam makes it $CONFIGURATION_DIRECTORY/toposlam.yaml).\n"
         "#\n"
         "# Made by `toposlam config --shipped` from the key table (src/config/config_keys.cpp); test_config_keys\n"
         "# checks that this file is what the table makes, so change a key's help or default there.\n"
         "# Every key is optional: an absent key keeps the default shown here (the built-in defaults are the\n"
         "# same, except `source`: the camera here, the simulator sim:office?route=loop2 without a config file).\n"
         "# `preset` comes first: it sets every stage's settings (fingerprint, similarity, segmentation,\n"
         "# topology) and the keys below override them; the values shown are the \"default\" preset's.\n"
         "# Unknown or repeated keys, wrong types and out-of-range values are refused at start, with the key's\n"
         "# full dotted name and its allowed range, e.g.\n"
         "#   toposlamd: error: /etc/toposlam/toposlam.yaml: pipeline.queues.frames: 0 is out of range, allowed 1 .. 1024 frames\n"
         "# Check a file without starting: toposlamd --check-config -c FILE; every key's effective value:\n"
         "# toposlamd --print-config -c FILE. All keys, with the thesis preset's values: docs/config.md.\n" +
         configYaml(shipped, true);
}

std::string configDocsMarkdown() {
  const DaemonConfig thesis = thesisConfig();
  std::string out =
      "# Config keys of toposlamd\n"
      "\n"
      "<!-- Made by `toposlam config --docs` from the key table (src/config/config_keys.cpp); test_config_keys\n"
      "     checks that this file is what the table makes. Edit the table, then regenerate. -->\n"
      "\n"
      "Every key of `config/toposlam.yaml`, with its default (the built-in value, which is the `default`\n"
      "method preset's), the `thesis` preset's value where it differs, the values allowed, the `toposlamd`\n"
      "option that overrides it and what it does. `preset` is read first and sets every stage's settings;\n"
      "the other keys override them. `toposlamd --print-config [-c FILE]` (or `toposlam config --print\n"
      "[-c FILE]`) shows the effective value of every key; `toposlamd --check-config -c FILE` validates a\n"
      "file. How the file is read and refused: [daemon.md](daemon.md#config).\n"
      "\n"
      "A key is added with one entry in `makeKeys()` of src/config/config_keys.cpp (path, member, default,\n"
      "range, unit, help); the reader, validation, `--print-config`, the shipped file and this page follow.\n";
  std::string section = "-";
  for (const ConfigKey& key : daemonConfigKeys()) {
    const std::size_t dot = key.path.find('.');
    const std::string top = dot == std::string::npos ? "" : key.path.substr(0, dot);
    if (top != section) {
      section = top;
      out += "\n## " + (top.empty() ? std::string("Top level") : "`" + top + "`") + "\n\n";
      if (!sectionHelp(top).empty()) out += sectionHelp(top) + ".\n\n";
      out += "| key | default | thesis | allowed | option | what it does |\n";
      out += "|---|---|---|---|---|---|\n";
    }
    const ConfigValue thesis_value = key.get(thesis);
    std::string thesis_text;
    if (key.path != "preset" && thesis_value != key.default_value) thesis_text = "`" + key.yamlText(thesis_value) + "`";
    std::string help;  // a '|' would end the table cell
    for (const char ch : key.help) {
      if (ch == '|') help += '\\';
      help += ch;
    }
    const std::string allowed = key.kind == ConfigKind::Flag ? std::string("true, false") : key.rangeText();
    std::string option;
    if (!key.option.empty()) option = "`" + key.option + "`";
    out += "| `" + key.path + "` | `" + key.yamlText(key.default_value) + "` | ";
    out += thesis_text + " | " + allowed + " | " + option + " | " + help + " |\n";
  }
  return out;
}

}  // namespace toposlam
