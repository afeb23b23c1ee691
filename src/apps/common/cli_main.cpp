// The command line's run of `toposlam` and `toposlam-bench`: see the header.
#include "cli_main.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>

#include <spdlog/spdlog.h>

#include "toposlam/config/daemon_config.hpp"
#include "toposlam/platform/logging.hpp"

namespace toposlam::cli {

namespace {

// What a command printed must have reached its reader: `toposlam fingerprint --json x > /dev/full` used to
// exit 0 with nothing written. stdout is flushed here, before exit would do it silently; a failure is
// exit 1 naming it (an error already reported keeps its own status).
int checkStandardOutput(int status, const std::string& program) {
  errno = 0;
  std::cout.flush();
  const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
  if (!failed) return status;
  const int error = errno;
  if (status == 0) {
    std::cerr << program << ": error: standard output: write failed"
              << (error != 0 ? std::string(": ") + std::strerror(error) : std::string()) << "\n";
  }
  return status == 0 ? 1 : status;
}

/// The first word of the command line that is neither an option nor --log-level's value: the command asked
/// for; empty when there is none.
std::string commandWord(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--log-level") {
      ++i;
    } else if (!word.empty() && word[0] != '-') {
      return word;
    }
  }
  return "";
}

/// "unknown command 'X'; the commands are: ..." when the command line's command is none of `app`'s (CLI11
/// alone says "A subcommand is required"); empty otherwise.
std::string unknownCommand(CLI::App& app, int argc, char** argv) {
  const std::string word = commandWord(argc, argv);
  if (word.empty() || !app.get_subcommands().empty()) return "";
  std::string names;
  bool known = false;
  for (const CLI::App* command : app.get_subcommands([](CLI::App*) { return true; })) {
    known = known || command->check_name(word);
    if (!command->get_group().empty()) names += (names.empty() ? "" : ", ") + command->get_name();
  }
  if (known) return "";
  return "unknown command '" + word + "'; the commands are: " + names + " (--help says what each does)";
}

int parse(CLI::App& app, int argc, char** argv, const std::string& program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command's own status, already explained on stderr
  } catch (const CLI::ParseError& e) {
    if (const std::string unknown = unknownCommand(app, argc, argv); !unknown.empty() && e.get_exit_code() != 0) {
      std::cerr << program << ": error: " << unknown << "\n";
      return 2;
    }
    const int code = app.exit(e);  // prints the help, the version or the usage error
    return code == 0 ? 0 : 2;
  } catch (const ConfigError& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

void addLogLevelOption(CLI::App& app) {
  app.fallthrough();
  app.add_option("--log-level", "log level: trace, debug, info, warn or error (default info)")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}))
      ->each([](const std::string& level) { spdlog::default_logger()->set_level(*parseLogLevel(level)); });
}

int runCommandLine(CLI::App& app, int argc, char** argv, const std::string& program) {
  return checkStandardOutput(parse(app, argc, argv, program), program);
}

}  // namespace toposlam::cli
