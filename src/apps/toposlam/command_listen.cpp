// `toposlam listen`: prints toposlamd's LCM messages as they arrive (place estimates, place events,
// topology, status), one line each, or one JSON object per line with --json. For people on the robot and
// for scripts: `toposlam listen --count 10 --json | jq .node`.
#include <chrono>
#include <csignal>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "toposlam/platform/lcm_transport.hpp"

namespace toposlam::cli {

namespace {

volatile std::sig_atomic_t g_interrupted = 0;
void onInterrupt(int) { g_interrupted = 1; }

std::vector<std::string> splitChannels(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

void addListenCommand(CLI::App& app) {
  struct Options {
    std::string url = "udpm://239.255.76.67:7667?ttl=0";
    std::string channels = "TOPOSLAM_PLACE,TOPOSLAM_PLACE_EVENT";
    long long count = 0;
    double timeout_s = 0.0;
    bool json = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("listen", "print toposlamd's place messages (LCM) as they arrive");
  cmd->add_option("--url", options->url, "LCM URL (toposlam.yaml lcm.url)")->capture_default_str();
  cmd->add_option("--channels", options->channels,
                  "comma-separated channels: TOPOSLAM_PLACE, TOPOSLAM_PLACE_EVENT, TOPOSLAM_TOPOLOGY, TOPOSLAM_STATUS, "
                  "TOPOSLAM_MOTION")
      ->capture_default_str();
  cmd->add_option("--count", options->count, "stop after N messages (0 = no limit)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--timeout", options->timeout_s, "stop after S seconds (0 = no limit); exit code 3 if nothing arrived")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", options->json, "one JSON object per line");
  cmd->callback([options] {
    const std::vector<std::string> channels = splitChannels(options->channels);
    if (channels.empty()) throw std::invalid_argument("--channels: give at least one channel");
    long long printed = 0;
    LcmSubscriber subscriber(options->url, LcmChannels{}, channels, [&](const ReceivedMessage& m) {
      if (options->count > 0 && printed >= options->count) return;
      std::cout << (options->json ? m.json : m.summary) << "\n" << std::flush;
      ++printed;
    });
    std::signal(SIGINT, onInterrupt);
    std::signal(SIGTERM, onInterrupt);
    const auto start = std::chrono::steady_clock::now();
    while (g_interrupted == 0 && (options->count == 0 || printed < options->count)) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (options->timeout_s > 0 && elapsed >= options->timeout_s) break;
      if (!subscriber.handle(100)) throw std::runtime_error("LCM receive failed on " + options->url);
    }
    if (subscriber.malformed() > 0)
      std::cerr << "toposlam listen: " << subscriber.malformed() << " messages could not be decoded\n";
    if (printed == 0 && options->timeout_s > 0) {
      std::cerr << "toposlam listen: no message within " << options->timeout_s << " s on " << options->url
                << " (is toposlamd running? same lcm.url and multicast route?)\n";
      throw CLI::RuntimeError(3);
    }
  });
}

}  // namespace toposlam::cli
