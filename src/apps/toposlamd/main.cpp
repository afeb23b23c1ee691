// toposlamd: the real-time topological SLAM service. Reads one config (default
// $CONFIGURATION_DIRECTORY/toposlam.yaml, then /etc/toposlam/toposlam.yaml, else built-in defaults),
// runs the pipeline and publishes over LCM. Thin: parses arguments, loads the config, runs daemon.cpp.
#include <csignal>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "daemon.hpp"
#include "sources.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/io/frame_source.hpp"
#include "toposlam/platform/logging.hpp"
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
  // Before the first log line: a closed log pipe must be a write error (EPIPE), not death by SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"toposlamd: real-time visual topological SLAM service, publishing places over LCM"};
  app.set_version_flag("--version", "toposlamd " TOPOSLAM_VERSION);  // project(VERSION), the package version
  std::string config_path;
  std::string source, map_path, lcm_url, overflow, record_dir;
  bool check_only = false, no_load = false, bench = false, resume_other_source = false;
  std::string log_level;
  double save_period = -1.0;
  toposlam::daemon::BenchOptions bench_options;
  app.add_option("-c,--config", config_path, "config file (YAML; see config/toposlam.yaml). Default: " +
                                                 toposlam::defaultDaemonConfigPath() + " if it exists, else built-in defaults");
  app.add_option("--source", source, "override `source` (e.g. sim:office?route=loop2, images:DIR, v4l2:/dev/video0)");
  auto* map_option = app.add_option("--map", map_path,
                                    "override `map.path` (relative paths resolve against $STATE_DIRECTORY; \"\" = never saved)");
  app.add_option("--lcm-url", lcm_url, "override `lcm.url`");
  app.add_option("--record", record_dir,
                 "override `record.dir`: record the frames processed into a new subfolder of DIR (replay: "
                 "images:DIR/<subfolder>?rate=recorded)");
  app.add_option("--overflow", overflow, "override `pipeline.queues.overflow`")->check(CLI::IsMember({"drop_oldest", "block"}));
  app.add_option("--save-period", save_period, "override `map.save_period_s` (seconds, 0 = only at stop)");
  app.add_flag("--no-map-load", no_load, "start a new map even if the map file exists");
  app.add_flag("--resume-other-source", resume_other_source,
               "override `map.resume_other_source`: continue a map made from another source");
  app.add_option("--log-level", log_level, "override `log.level`: trace, debug, info, warn or error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  app.add_flag("--check-config", check_only, "validate the config, print the result and exit");
  app.add_flag("--bench", bench, "benchmark: fps and capture-to-publish latency at 320x240 and 640x480, then exit");
  app.add_option("--bench-frames", bench_options.frames, "frames per benchmark run")->check(CLI::Range(10, 100000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the help, the version or the usage error
    return code == 0 ? 0 : 2;      // CLI11's own codes (105-109, ...) are usage errors: 2
  }
  // stderr, in the journal's format under systemd; the level of --log-level, else info until the config
  // has been read (its log.level then applies).
  const bool journal = g_journal = toposlam::configureLogging("toposlamd", *toposlam::parseLogLevel(log_level.empty() ? "info" : log_level));

  try {
    toposlam::DaemonConfig config;
    const bool explicit_config = !config_path.empty();
    if (!explicit_config) config_path = toposlam::defaultDaemonConfigPath();
    if (explicit_config || std::filesystem::exists(config_path)) {
      config = toposlam::loadDaemonConfig(config_path);
    } else {
      config_path = "(built-in defaults)";
    }
    if (!source.empty()) config.source = source;
    if (map_option->count() > 0) config.pipeline.map_path = map_path;  // --map "" means no map file
    if (!lcm_url.empty()) config.lcm.url = lcm_url;
    if (!record_dir.empty()) config.record.dir = record_dir;
    if (overflow == "block") config.pipeline.queues.overflow = toposlam::QueueOverflow::Block;
    if (overflow == "drop_oldest") config.pipeline.queues.overflow = toposlam::QueueOverflow::DropOldest;
    if (save_period >= 0.0) config.pipeline.map_save_period_s = save_period;
    if (no_load) config.load_map_at_start = false;
    if (resume_other_source) config.map_resume_other_source = true;
    if (!log_level.empty()) config.log_level = log_level;
    spdlog::default_logger()->set_level(*toposlam::parseLogLevel(config.log_level));
    if (std::string problem = config.validate(); !problem.empty())
      throw toposlam::ConfigError("command line: " + problem);
    if (check_only) {
      if (const std::string problem = toposlam::daemon::checkSourceUri(config.source); !problem.empty())
        throw toposlam::ConfigError(config_path + ": source: " + problem);
      std::cout << "toposlamd: config OK: " << config_path << "\n";
      return 0;
    }
    spdlog::info("toposlamd: config {}; logging at {} to {}", config_path, config.log_level,
                 journal ? "the journal (priorities, no timestamps)" : "stderr");
    if (bench) {
      bench_options.source = config.source;
      return toposlam::daemon::runBench(config, bench_options);
    }
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
