// `toposlam view`: the live view, a web page of what toposlamd publishes over LCM (the topology as a graph
// with a thumbnail per node, the node the robot is in now, the last revisits beside the places they
// matched, the status line), updated by Server-Sent Events.
//
// The server is Python's standard library (view/live_view.py, beside the package toposlam_lcm and its
// multicast reader), so it costs the build nothing. This command reads toposlamd's config as `listen`
// does (-c FILE, else the same look-up as toposlamd) for lcm.url and the channel names, checks the
// options, then replaces itself with `python3 live_view.py ...` (exec: the same process id, so a stop
// signal or a unit's Kill reaches the server, whose exit status is the command's: 0 after SIGINT/SIGTERM,
// 1 a port in use, 2 a bad address).
//
// live_view.py is looked for under the installed prefix (<bindir>/../TOPOSLAM_VIEW_INSTALL_DIR), then in
// the source tree; the package toposlam_lcm under <prefix>/TOPOSLAM_PYTHON_INSTALL_DIR, then in the build
// tree. $TOPOSLAM_VIEW_DIR overrides the first.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "lcm_channels.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/config/daemon_config.hpp"

namespace toposlam::cli {

namespace {

namespace fs = std::filesystem;

/// The folder holding this program's installation prefix (bindir's parent), empty when unknown.
fs::path installPrefix() {
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  return error ? fs::path() : program.parent_path().parent_path();
}

/// The first of candidates holding file, else throws naming every folder looked in.
fs::path firstHolding(const std::vector<fs::path>& candidates, const std::string& file,
                      const std::string& what) {
  std::string searched;
  for (const fs::path& folder : candidates) {
    std::error_code error;
    if (!folder.empty() && fs::exists(folder / file, error)) return folder.lexically_normal();
    searched += (searched.empty() ? "" : ", ") + folder.string();
  }
  throw std::runtime_error("view: " + what + " not found (looked in " + searched +
                           "); is toposlam fully installed?");
}

/// PYTHONPATH with folder first, so the toposlam_lcm found is the one of this installation.
void prependPythonPath(const fs::path& folder) {
  const char* old = std::getenv("PYTHONPATH");
  const std::string value = folder.string() + (old && *old ? ":" + std::string(old) : std::string());
  ::setenv("PYTHONPATH", value.c_str(), 1);
}

}  // namespace

void addViewCommand(CLI::App& app) {
  struct Options {
    std::string config;
    std::string lcm_url;
    std::string bind = "127.0.0.1";
    int port = 8080;
  };
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "view",
      "serve a live web page of toposlamd's map: the topology with a thumbnail per node, the current node, "
      "the last revisits and the status, updated as LCM messages arrive (Ctrl-C ends it)");
  cmd->add_option("-c,--config", options->config,
                  "toposlamd's config, for lcm.url and lcm.channels (default: " + defaultDaemonConfigPath() +
                      " if it exists, else the built-in defaults)");
  cmd->add_option("--lcm-url", options->lcm_url, "LCM URL (default: the config's lcm.url)");
  cmd->add_option("--port", options->port, "TCP port of the page (default 8080)")
      ->check(CLI::Range(1, 65535));
  cmd->add_option(
      "--bind", options->bind,
      "address to listen on (default 127.0.0.1: this host only; 0.0.0.0: every network, e.g. to open "
      "it from a laptop on the robot's network)");
  cmd->callback([options] {
    DaemonConfig config;
    const std::string config_path = options->config.empty() ? defaultDaemonConfigPath() : options->config;
    if (!options->config.empty() || fs::exists(config_path)) config = loadDaemonConfig(config_path);
    const LcmChannels channels = channelsOf(config.lcm);
    const std::string url = options->lcm_url.empty() ? config.lcm.url : options->lcm_url;
    if (url.rfind("udpm://", 0) != 0)
      throw CLI::ValidationError("--lcm-url",
                                 "the live view listens on udpm:// URLs only, not '" + url + "'");

    const fs::path prefix = installPrefix();
    std::vector<fs::path> view_folders;
    if (const char* explicit_dir = std::getenv("TOPOSLAM_VIEW_DIR"); explicit_dir && *explicit_dir)
      view_folders.emplace_back(explicit_dir);
    view_folders.push_back(prefix.empty() ? fs::path() : prefix / TOPOSLAM_VIEW_INSTALL_DIR);
    view_folders.emplace_back(TOPOSLAM_VIEW_SOURCE_DIR);
    const fs::path script =
        firstHolding(view_folders, "live_view.py", "the live view's live_view.py") / "live_view.py";
    prependPythonPath(firstHolding({prefix.empty() ? fs::path() : prefix / TOPOSLAM_PYTHON_INSTALL_DIR,
                                    fs::path(TOPOSLAM_LCM_BUILD_PYTHONPATH)},
                                   "toposlam_lcm/udpm_reader.py", "the Python package toposlam_lcm"));
    ::setenv("PYTHONDONTWRITEBYTECODE", "1", 1);  // nothing written beside an installed script

    std::vector<std::string> args{"python3",
                                  script.string(),
                                  "--port",
                                  std::to_string(options->port),
                                  "--bind",
                                  options->bind,
                                  "--lcm-url",
                                  url,
                                  "--place-channel",
                                  channels.place,
                                  "--place-event-channel",
                                  channels.place_event,
                                  "--topology-channel",
                                  channels.topology,
                                  "--status-channel",
                                  channels.status};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::cout.flush();
    std::cerr.flush();
    ::execvp("python3", argv.data());
    throw std::runtime_error(std::string("view: cannot run python3 (Debian package python3): ") +
                             std::strerror(errno));
  });
}

}  // namespace toposlam::cli
