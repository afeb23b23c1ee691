// `toposlam config`: toposlamd's config as the key table makes it: the effective config of a file (or of
// the built-in defaults) with every key, the shipped config/toposlam.yaml, or docs/config.md.
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/config/config_text.hpp"
#include "toposlam/config/daemon_config.hpp"

namespace toposlam::cli {

void addConfigCommand(CLI::App& app) {
  struct Options {
    std::string config;
    bool print = false;
    bool shipped = false;
    bool docs = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "config", "print toposlamd's effective config (every key), or the shipped config / docs table made from the key table");
  cmd->add_option("-c,--config", options->config,
                  "the config file to read (default: " + defaultDaemonConfigPath() +
                      " if it exists, else the built-in defaults)");
  cmd->add_flag("--print", options->print, "print the effective config as YAML, every key (the default action)");
  auto* shipped = cmd->add_flag("--shipped", options->shipped, "print config/toposlam.yaml as the key table makes it");
  cmd->add_flag("--docs", options->docs, "print docs/config.md as the key table makes it")->excludes(shipped);
  cmd->callback([options] {
    if (options->shipped) {
      std::cout << shippedConfigYaml();
      return;
    }
    if (options->docs) {
      std::cout << configDocsMarkdown();
      return;
    }
    DaemonConfig config;
    std::string path = options->config.empty() ? defaultDaemonConfigPath() : options->config;
    if (!options->config.empty() || std::filesystem::exists(path)) {
      config = loadDaemonConfig(path);
    } else {
      path = "(built-in defaults)";
    }
    std::cout << "# toposlamd's effective config: " << path << "\n" << configYaml(config, false);
  });
}

}  // namespace toposlam::cli
