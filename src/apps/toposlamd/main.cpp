// toposlamd: the real-time topological SLAM service. Reads one config (default
// $CONFIGURATION_DIRECTORY/toposlam.yaml, then the install's <sysconfdir>/toposlam/toposlam.yaml, then
// /etc/toposlam/toposlam.yaml, else built-in defaults: config_path.hpp), runs the pipeline and publishes
// over LCM. Thin: parses arguments, loads the config, runs daemon.cpp.
#include <csignal>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "config_key_cli.hpp"
#include "daemon.hpp"
#include "sources.hpp"
#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/config/config_text.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "toposlam/platform/logging.hpp"
#include "toposlam/platform/opencv_runtime.hpp"
#include "toposlam/platform/signal_mask.hpp"
#include "toposlam/topology/map_store.hpp"

namespace {

bool g_journal = false;  // stderr is the journal: the error line carries its priority, "<3>" (LOG_ERR)

int startError(const std::exception& e, int code) {
  std::cerr << (g_journal ? "<3>" : "") << "toposlamd: error: " << e.what() << "\n";
  return code;
}

}  // namespace

// Exit status: 0 ok (end of stream or a stop signal), 1 runtime error (LCM, the pipeline failed), 2 usage or
// config error: a bad option, config, source or map that no restart fixes (the unit's
// RestartPreventExitStatus=2).
int main(int argc, char** argv) {
  toposlam::keepOpenCvOffOpenCl();  // before any OpenCV call
  // Before the first log line: a closed log pipe must be a write error (EPIPE), not death by SIGPIPE; a
  // write beyond ulimit -f one too (EFBIG), not death by SIGXFSZ.
  toposlam::ignoreSignals({SIGPIPE, SIGXFSZ});
  CLI::App app{"toposlamd: real-time visual topological SLAM service, publishing places over LCM"};
  app.set_version_flag("--version", "toposlamd " TOPOSLAM_VERSION);  // project(VERSION), the package version
  std::string config_path;
  bool check_only = false, print_config = false;
  app.add_option("-c,--config", config_path, "config file (YAML; see config/toposlam.yaml and docs/config.md). Default: " +
                                                 toposlam::defaultDaemonConfigPath() + " if it exists, else built-in defaults");
  // The override options come from the key table (config_keys.cpp): one per key that names one.
  const toposlam::cli::ConfigKeyOptions<toposlam::DaemonConfig> key_options(app, toposlam::daemonConfigKeys());
  std::vector<std::string> sets;
  app.add_option("--set", sets,
                 "set any key of the config: --set KEY=VALUE (repeatable; keys and values as in the YAML, "
                 "docs/config.md), applied after the file and the options above")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app.add_flag("--check-config", check_only, "validate the config, print the result and exit");
  app.add_flag("--print-config", print_config,
               "print the effective config (file, defaults and options) as YAML with every key, and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the help, the version or the usage error
    return code == 0 ? 0 : 2;      // CLI11's own codes (105-109, ...) are usage errors: 2
  }
  // stderr, in the journal's format under systemd; the level of --log-level, else info until the config
  // has been read (its log.level then applies).
  const std::string* level_option = key_options.given("log_level");
  const bool journal = g_journal =
      toposlam::configureLogging("toposlamd", *toposlam::parseLogLevel(level_option ? *level_option : "info"));

  try {
    const bool explicit_config = !config_path.empty();
    if (!explicit_config) config_path = toposlam::defaultDaemonConfigPath();
    const bool read_file = explicit_config || std::filesystem::exists(config_path);
    std::vector<toposlam::ConfigOverride> given_overrides = key_options.overrides();
    for (const std::string& set : sets) given_overrides.push_back(toposlam::parseSetOverride(set));
    const bool options_given = !given_overrides.empty();
    const toposlam::DaemonConfig config =
        toposlam::commandLineConfig(read_file ? config_path : std::string(), given_overrides);
    if (!read_file) config_path = "(built-in defaults)";
    spdlog::default_logger()->set_level(*toposlam::parseLogLevel(config.log_level));
    if (print_config) {
      std::cout << "# toposlamd's effective config: " << config_path << (options_given ? " and the options" : "")
                << "\n" << toposlam::configYaml(config, false);
      return 0;
    }
    if (check_only) {
      if (const std::string problem = toposlam::daemon::checkSourceUri(config.source); !problem.empty())
        throw toposlam::ConfigError(config_path + ": source: " + problem);
      std::cout << "toposlamd: config OK: " << config_path << "\n";
      return 0;
    }
    spdlog::info("toposlamd: config {}; logging at {} to {}", config_path, config.log_level,
                 journal ? "the journal (priorities, no timestamps)" : "stderr");
    return toposlam::daemon::runDaemon(config);
  } catch (const toposlam::ConfigError& e) {
    return startError(e, 2);
  } catch (const toposlam::FrameSourceError& e) {
    return startError(e, 2);  // the configured source cannot be opened as given (URI, path, permissions)
  } catch (const toposlam::MapStoreError& e) {
    return startError(e, 2);  // the map is locked by another process, too large, or made with other settings
  } catch (const std::exception& e) {
    return startError(e, 1);  // e.g. LCM cannot open yet (no network, no multicast route): a restart may help
  }
}
