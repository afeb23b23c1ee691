// Texts made from the config key table (config_keys.hpp): the effective config as YAML (toposlamd
// --print-config, `toposlam config --print`), the shipped config/toposlam.yaml with every key's help as
// its comment (`toposlam config --shipped`), and docs/config.md's key table (`toposlam config --docs`).
// test_config_keys keeps both checked-in files equal to what these return.
#pragma once

#include <string>

namespace toposlam {

struct DaemonConfig;

/// Every key of `config` as YAML, in the table's order; `preset` first, so reading the text back gives
/// `config` again. With `comments`, each section and key is preceded by its help, allowed values, unit
/// and, where the thesis preset differs, the thesis preset's value.
std::string configYaml(const DaemonConfig& config, bool comments);

/// The installed config: the defaults with the robot's camera as the source, fully commented.
std::string shippedConfigYaml();
/// The source of the installed config (the built-in default is the simulator).
inline constexpr const char* kShippedSource = "v4l2:/dev/video0";

/// docs/config.md: every key with its default, thesis preset value, allowed values, option and help.
std::string configDocsMarkdown();

}  // namespace toposlam
