// `toposlam listen`: prints toposlamd's LCM messages as they arrive (place estimates, place events,
// topology, status), one line each, or one JSON object per line with --json. For people on the robot and
// for scripts: `toposlam listen --count 10 --json | jq .node`.
//
// It reads the daemon's config (-c FILE, else the same look-up as toposlamd) for lcm.url and the channel
// names, so a robot whose config renames the channels needs no extra options. Ctrl-C and SIGTERM end it
// with exit status 0 (and, with --hz, the per-channel message rates). A STATUS line ends with the motion
// input's state ("motion stale (segmenting by time), ..., motion refused 20"); listening live, --hz also
// says how many motion messages were stamped further than segmentation.motion.clock_tolerance_s from this
// host's CLOCK_MONOTONIC, the messages toposlamd on this host refuses.
//
// `--from lcmlog:FILE` replays a recorded LCM log instead (lcm-logger's format, or toposlamd's own with
// `lcm.url: file://FILE?mode=w`), read with the pure LcmLogReader: the same lines, as fast as read; --hz
// rates over the log's own time. `--run-folder DIR` also turns it into a run folder for `toposlam report`.
// A corrupt or truncated log is an error naming the byte offset (after the messages before it).
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "commands.hpp"
#include "lcm_channels.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "lcmlog_run_folder.hpp"
#include "toposlam/platform/lcm_log.hpp"
#include "toposlam/platform/lcm_log_run.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam/platform/signal_mask.hpp"

namespace toposlam::cli {

namespace {

volatile std::sig_atomic_t g_interrupted = 0;
void onInterrupt(int) { g_interrupted = 1; }

/// The signals that stop `listen`.
const std::vector<int>& stopSignals() {
  static const std::vector<int> signals{SIGINT, SIGTERM};
  return signals;
}

// LCM's udpm provider receives on a thread of its own; blocked there, a stop signal always reaches this
// (the calling) thread, whose select() then returns EINTR.
void blockStopSignals() { blockSignals(stopSignals()); }

// Without SA_RESTART (catchSignals): the handler only sets the flag, and the wait in select() returns
// EINTR (which LcmSubscriber::handle treats as "look at the flag"), so the exit follows the signal at once.
void catchStopSignals() { catchSignals(stopSignals(), onInterrupt); }

std::vector<std::string> splitChannels(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// A --channels item is a channel name of the config or one of its keys (place, place_event, topology,
// status, motion), which stands for the name the config gives it.
std::string resolveChannel(const std::string& item, const LcmChannels& known) {
  if (item == "place") return known.place;
  if (item == "place_event") return known.place_event;
  if (item == "topology") return known.topology;
  if (item == "status") return known.status;
  if (item == "motion") return known.motion;
  return item;
}

/// Why a --channels item names no channel: the keys and names it could have been, where those names come
/// from (the config file read, or the built-in defaults when there is none), and a near miss.
std::string unknownChannelText(const std::string& item, const LcmChannels& known, const std::string& names_from) {
  std::string text = "unknown channel '" + item + "'";
  for (const char* key : {"place", "place_event", "topology", "status", "motion"}) {
    if (item.size() > 1 && (item == std::string(key) + "s" || item + "s" == key))
      text += " (did you mean '" + std::string(key) + "'?)";
  }
  return text + "; give a key (place, place_event, topology, status, motion) or a channel name (" + known.place +
         ", " + known.place_event + ", " + known.topology + ", " + known.status + ", " + known.motion + "; " +
         names_from + ")";
}

/// CLOCK_MONOTONIC (steady_clock on Linux), seconds: the clock of motion_t.utime on this host.
double monotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string formatRate(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", value);
  return text;
}

}  // namespace

void addListenCommand(CLI::App& app) {
  struct Options {
    std::string config;
    std::string url;
    std::string channels;
    long long count = 0;
    double timeout_s = 0.0;
    bool json = false;
    bool hz = false;
    std::string from;
    std::string run_folder;
  };
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("listen", "print toposlamd's place messages (LCM) as they arrive");
  cmd->add_option("-c,--config", options->config,
                  "toposlamd's config, for lcm.url and lcm.channels (default: " + defaultDaemonConfigPath() +
                      " if it exists, else the built-in defaults)");
  cmd->add_option("--url", options->url, "LCM URL (default: the config's lcm.url)");
  cmd->add_option("--channels", options->channels,
                  "comma-separated channels, by name or by config key: place, place_event, topology, status, motion "
                  "(default: place,place_event)");
  cmd->add_option("--count", options->count, "stop after N messages (0 = no limit)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--timeout", options->timeout_s, "stop after S seconds (0 = no limit); exit status 1 if nothing arrived")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", options->json, "one JSON object per line");
  cmd->add_flag("--hz", options->hz, "at the end, print each channel's message count and rate (messages per second)");
  auto* from = cmd->add_option("--from", options->from,
                               "replay a recorded LCM log instead of listening: lcmlog:FILE (lcm-logger's format)");
  cmd->add_option("--run-folder", options->run_folder,
                  "with --from: also write the run as a run folder (frames.csv, places.csv, topology.json, "
                  "thumbnails) for `toposlam report`")
      ->needs(from);
  cmd->callback([options] {
    DaemonConfig config;
    const std::string config_path = options->config.empty() ? defaultDaemonConfigPath() : options->config;
    const bool read_config = !options->config.empty() || std::filesystem::exists(config_path);
    if (read_config) config = loadDaemonConfig(config_path);
    const std::string names_from = read_config ? "names from " + config_path
                                               : "the built-in names: there is no config at " + config_path;
    const LcmChannels known = channelsOf(config.lcm);
    const std::string url = options->url.empty() ? config.lcm.url : options->url;

    std::vector<std::string> channels;
    for (const std::string& item : splitChannels(options->channels.empty() ? "place,place_event" : options->channels))
      channels.push_back(resolveChannel(item, known));
    if (channels.empty()) throw CLI::ValidationError("--channels", "give at least one channel");
    for (const std::string& c : channels)
      if (c != known.place && c != known.place_event && c != known.topology && c != known.status && c != known.motion)
        throw CLI::ValidationError("--channels", unknownChannelText(c, known, names_from));

    long long printed = 0;
    std::map<std::string, long long> per_channel;
    for (const std::string& c : channels) per_channel[c] = 0;
    // Motion messages stamped off this host's clock, live only (a log's times are not this clock's).
    long long motion_off_clock = 0;
    bool live = false;
    auto printRates = [&](double seconds) {
      if (!options->hz) return;
      for (const auto& [channel, n] : per_channel) {
        const std::string hz = formatRate(seconds > 0 ? static_cast<double>(n) / seconds : 0.0);
        const bool off_clock_known = live && channel == known.motion;
        if (options->json) {
          std::cout << "{\"rate\":{\"channel\":\"" << JsonWriter::escape(channel) << "\",\"messages\":" << n
                    << ",\"seconds\":" << formatRate(seconds) << ",\"hz\":" << hz;
          if (off_clock_known) std::cout << ",\"off_clock\":" << motion_off_clock;
          std::cout << "}}\n";
        } else {
          std::cout << "rate " << channel << ": " << n << " messages in " << formatRate(seconds) << " s = " << hz
                    << " Hz";
          if (off_clock_known)
            std::cout << ", " << motion_off_clock << " stamped more than "
                      << formatRate(config.segmentation_stage.motion.clock_tolerance_s)
                      << " s off this host's clock (refused by toposlamd)";
          std::cout << "\n";
        }
      }
      std::cout << std::flush;
    };
    if (!options->from.empty()) {
      if (options->from.rfind("lcmlog:", 0) != 0 || options->from.size() == 7)
        throw CLI::ValidationError("--from", "'" + options->from + "' is not lcmlog:FILE");
      const std::string path = options->from.substr(7);
      // The messages first (each decoded as a live subscriber would), then the run folder if asked.
      LcmLogReader reader(path);
      std::int64_t first_utime = 0, last_utime = 0, malformed = 0, events = 0;
      for (LcmLogEvent event; reader.next(event);) {
        if (events++ == 0) first_utime = event.utime;
        last_utime = event.utime;
        const auto wanted = per_channel.find(event.channel);
        if (wanted == per_channel.end()) continue;
        ReceivedMessage m;
        if (!decodeLcmMessage(channelKind(known, event.channel), event.channel, event.data.data(), event.data.size(), m)) {
          ++malformed;
          continue;
        }
        ++wanted->second;
        if (options->count > 0 && printed >= options->count) continue;
        std::cout << (options->json ? m.json : m.summary) << "\n";
        ++printed;
      }
      std::cout << std::flush;
      printRates(static_cast<double>(last_utime - first_utime) * 1e-6);
      if (malformed > 0) std::cerr << "toposlam listen: " << malformed << " messages could not be decoded\n";
      if (!options->run_folder.empty()) {
        const LoggedRun run = readLoggedRun(path, known);
        writeRunFolderFromLog(run, path, options->run_folder);
        std::cerr << "listen: wrote the run folder " << options->run_folder << " (" << run.frames.size()
                  << " place estimates, " << run.places.size() << " places); toposlam report " << options->run_folder
                  << "\n";
      }
      return;
    }
    blockStopSignals();  // until the handlers are in place: a signal now waits for them
    live = true;
    LcmSubscriber subscriber(url, known, channels, [&](const ReceivedMessage& m) {
      ++per_channel[m.channel];
      if (m.kind == "motion" && !(std::abs(m.motion_time_s - monotonicSeconds()) <=
                                  config.segmentation_stage.motion.clock_tolerance_s))
        ++motion_off_clock;
      if (options->count > 0 && printed >= options->count) return;
      std::cout << (options->json ? m.json : m.summary) << "\n" << std::flush;
      ++printed;
    });
    catchStopSignals();
    const auto start = std::chrono::steady_clock::now();
    while (g_interrupted == 0 && (options->count == 0 || printed < options->count)) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (options->timeout_s > 0 && elapsed >= options->timeout_s) break;
      if (!subscriber.handle(100)) throw std::runtime_error("LCM receive failed on " + url);
    }
    printRates(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (subscriber.malformed() > 0)
      std::cerr << "toposlam listen: " << subscriber.malformed() << " messages could not be decoded\n";
    if (subscriber.fragments_abandoned() > 0)
      std::cerr << "toposlam listen: " << subscriber.fragments_abandoned()
                << " fragmented messages were abandoned unfinished (a fragment lost)\n";
    if (printed == 0 && options->timeout_s > 0 && g_interrupted == 0) {
      std::ostringstream message;
      message << "listen: no message within " << options->timeout_s << " s on " << url
              << " (is toposlamd running? same lcm.url and multicast route?)";
      throw std::runtime_error(message.str());
    }
  });
}

}  // namespace toposlam::cli
