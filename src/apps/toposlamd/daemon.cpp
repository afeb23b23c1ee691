// toposlamd's body; see daemon.hpp. Signals are blocked in every thread (the mask is set before any thread
// exists, threads inherit it) and taken synchronously by the main thread (waitForSignal, platform/os), so no work
// happens in a signal handler:
//   SIGTERM, SIGINT, SIGHUP, SIGQUIT and every other signal that would end the process and can be taken
//   (SIGXCPU, SIGPWR, SIGVTALRM, SIGPROF, SIGIO, SIGSYS, SIGSTKFLT, SIGRTMIN..SIGRTMAX; platform/os,
//   catchableTerminatingSignals)
//                                      finish the filter step in progress, save the map, exit 0
//   SIGUSR1, SIGUSR2, SIGALRM          logged and otherwise ignored (their default would kill the daemon
//                                      without a final save)
//   SIGPIPE, SIGXFSZ                   ignored: a write to a closed pipe (a log reader gone) fails with
//                                      EPIPE, one beyond the file-size limit (ulimit -f) with EFBIG, which
//                                      the writers treat as a failed write (a map save is retried, the
//                                      previous map kept), not as the end
//   SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP, SIGABRT, SIGKILL, SIGSTOP: their default (nothing trusted to
//                                      save, or nothing to catch)
#include "daemon.hpp"

#include <algorithm>
#include <atomic>
#include <csignal>
#include <iterator>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <sstream>
#include <vector>

#include <spdlog/spdlog.h>

#include "lcm_channels.hpp"
#include "sources.hpp"
#include "toposlam/config/config_keys.hpp"
#include "toposlam/core/worker_pool.hpp"
#include "toposlam/io/recording_frame_source.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/map_files.hpp"
#include "toposlam/pipeline/pipeline.hpp"
#include "toposlam/pipeline/stage_assembly.hpp"
#include "toposlam/pipeline/thread_table.hpp"
#include "toposlam/platform/file_system.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam/platform/signal_mask.hpp"
#include "toposlam/platform/systemd_notifier.hpp"
#include "toposlam/platform/thread_os.hpp"
#include "toposlam/topology/map_store.hpp"

namespace toposlam::daemon {

namespace {

/// Taken by the main thread, logged and otherwise ignored; every other signal it takes stops the daemon.
constexpr int kIgnoredSignals[] = {SIGUSR1, SIGUSR2, SIGALRM};
/// Ignored by the process: the write that raised one fails instead (EPIPE, EFBIG).
const std::vector<int> kWriteSignals = {SIGPIPE, SIGXFSZ};

bool isStopSignal(int signal) {
  return signal != 0 &&
         std::find(std::begin(kIgnoredSignals), std::end(kIgnoredSignals), signal) == std::end(kIgnoredSignals);
}

/// Every signal the main thread takes with waitForSignal (stop and ignored ones): every signal that would end
/// the process and can be caught.
std::vector<int> handledSignalNumbers() { return catchableTerminatingSignals(); }

/// Proves at start that the map can be saved, before any frame (MapStore::checkWritable, exit 2 otherwise),
/// and says when a file-size limit may stop a later save.
void checkMapSavable(const std::string& path) {
  if (path.empty()) return;
  MapStore::checkWritable(path);
  if (const std::uint64_t limit = fileSizeLimitBytes(); limit > 0) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    spdlog::warn("toposlamd: files are limited to {} bytes here (ulimit -f){}: a map save beyond it fails (EFBIG), "
                 "is retried and reported, and the previous map is kept", limit,
                 ec ? std::string() : "; the map " + path + " is " + std::to_string(size) + " bytes");
  }
}

/// The fingerprint stage's pool threads (tsl-vpack-1, ...) take the fingerprint thread's scheduling from
/// pipeline.threads.fingerprint (policy, priority, nice), so the stage's work runs at one priority. Not its
/// CPU: the pool exists to run on the other cores. A setting that cannot be applied is logged, not fatal.
std::function<void(int)> fingerprintWorkers(const ThreadSettings& fingerprint) {
  return [fingerprint](int worker) {
    ThreadSettings settings = fingerprint;
    settings.name = "tsl-vpack-" + std::to_string(worker);
    settings.cpu = -1;
    for (const std::string& problem : applyThreadSettings(settings)) spdlog::warn("thread {}", problem);
  };
}

/// Everything one run needs: the source, the fingerprint's worker pool and the stages (the one assembly the
/// offline commands use too, stage_assembly.hpp).
struct Assembly {
  std::unique_ptr<FrameSource> source;
  std::unique_ptr<WorkerPool> pool;
  StageAssembly stages;

  Assembly(const DaemonConfig& config, const Clock& clock, const std::string& source_uri)
      : source(openSource(source_uri)),
        pool(std::make_unique<WorkerPool>(config.fingerprint_stage.workers,
                                          fingerprintWorkers(config.pipeline.threads.fingerprint))),
        stages(config, clock, pool.get(), Thumbnails::Kept) {}
};

/// Until the host has a route to LCM's multicast group (lcm.open_retry_s apart): a service started before
/// the network must wait for it, not exit and burn systemd's start limit. Says so in the log (at the
/// first attempt, then once a minute) and in STATUS=; READY=1 at the first miss (started, waiting: no
/// start timeout), watchdog pings meanwhile. False when a stop signal came first.
bool waitForNetwork(const DaemonConfig& config, const std::vector<int>& signals, const SystemdNotifier& notifier,
                    double watchdog_s, const Clock& clock) {
  const double period = config.lcm.open_retry_s;
  if (period <= 0) return true;  // no waiting: opening LCM throws with the hint (exit 1)
  const double start = clock.now();
  double last_log = start;
  int attempts = 0;
  for (std::string problem; !(problem = lcmRouteProblem(config.lcm.url)).empty();) {
    ++attempts;
    const double waited = clock.now() - start;
    if (attempts == 1) {
      spdlog::warn("toposlamd: waiting for the network: {} (lcm.url {}); trying again every {} s (the multicast "
                   "route: docs/deploy.md)", problem, config.lcm.url, period);
      notifier.ready();
    } else if (clock.now() - last_log >= 60.0) {
      spdlog::warn("toposlamd: still waiting for the network after {:.0f} s ({} attempts): {}", waited, attempts, problem);
      last_log = clock.now();
    }
    notifier.status("waiting for the network: " + problem + " (lcm.url " + config.lcm.url + ", attempt " +
                    std::to_string(attempts) + ")");
    const double until = clock.now() + period;
    for (double left = period; left > 0; left = until - clock.now()) {
      const int signal = waitForSignal(signals, watchdog_s > 0 ? std::min(left, watchdog_s / 2.0) : left);
      if (signal != 0 && isStopSignal(signal)) {
        spdlog::info("toposlamd: {} received while waiting for the network: nothing to save, exiting", strsignal(signal));
        notifier.stopping();
        return false;
      }
      if (signal != 0) spdlog::info("toposlamd: {} received: ignored", strsignal(signal));
      if (watchdog_s > 0) notifier.watchdog();
    }
  }
  if (attempts > 0)
    spdlog::info("toposlamd: the network is up after {} attempts ({:.1f} s); opening LCM at {}", attempts + 1,
                 clock.now() - start, config.lcm.url);
  return true;
}

/// Wraps the source in a RecordingFrameSource when record.dir is set. Recording is an extra: a folder that
/// cannot be made, or a bound already reached by earlier recordings, is logged as an error and the daemon
/// runs without it (the robot keeps mapping). Returns the recorder, or null.
RecordingFrameSource* startRecording(const RecordSettings& settings, std::unique_ptr<FrameSource>& source) {
  if (settings.dir.empty()) return nullptr;
  const std::filesystem::path parent = resolveMapPath(settings.dir);
  const auto bound = static_cast<std::uint64_t>(settings.max_mb * 1024.0 * 1024.0);
  const std::uint64_t kept = bytesUnder(parent);
  if (kept >= bound) {
    spdlog::error("toposlamd: not recording: {} already holds {:.1f} MB of recordings, record.max_mb is {} MB; remove "
                  "old recordings (or raise record.max_mb) to record again",
                  parent.string(), static_cast<double>(kept) / (1024.0 * 1024.0), settings.max_mb);
    return nullptr;
  }
  FrameRecorderConfig recorder_config;
  recorder_config.format = settings.format;
  recorder_config.jpeg_quality = settings.jpeg_quality;
  recorder_config.max_bytes = bound - kept;  // what is left of the bound over all recordings in the folder
  const std::filesystem::path folder = newRecordingFolder(parent, static_cast<std::int64_t>(std::time(nullptr)));
  std::unique_ptr<FrameRecorder> recorder;
  try {
    recorder = std::make_unique<FrameRecorder>(folder, recorder_config);
  } catch (const FrameSourceError& e) {
    spdlog::error("toposlamd: not recording: {} (record.dir {}); running without recording", e.what(), settings.dir);
    return nullptr;
  }
  auto recording = std::make_unique<RecordingFrameSource>(std::move(source), std::move(recorder), settings.queue_frames);
  RecordingFrameSource* raw = recording.get();
  source = std::move(recording);
  spdlog::info("toposlamd: recording the frames into {} ({}, at most {:.1f} MB; replay: images:{}?rate=recorded)",
               folder.string(), settings.format, static_cast<double>(recorder_config.max_bytes) / (1024.0 * 1024.0),
               folder.string());
  return raw;
}

/// The recording part of the status line: "recording 120 frames (3.1 MB, 0 dropped)", or why it stopped.
std::string recordingStatus(const RecordingFrameSource& recording) {
  const RecordingStatus s = recording.status();
  char text[160];
  std::snprintf(text, sizeof text, "%lld frames (%.1f MB, %lld dropped)", static_cast<long long>(s.written),
                static_cast<double>(s.bytes) / (1024.0 * 1024.0), static_cast<long long>(s.dropped));
  switch (s.state) {
    case RecordingState::Recording: return std::string("recording ") + text;
    case RecordingState::Full: return std::string("recording stopped at record.max_mb: ") + text;
    case RecordingState::Failed: return "recording failed (" + s.problem + "): " + text;
    case RecordingState::Finished: return std::string("recorded ") + text;
  }
  return text;
}

/// A resumed map from a source that names its frames (images:) records the last frame it holds: the source
/// continues after it, so that a restart (Restart=on-failure, a reboot) maps each frame once. Unless
/// map.source_from_start, or the source has no such frame (then it starts from its first, said in the log).
void continueSource(const MapSettings& recorded, const DaemonConfig& config, FrameSource& source,
                    ParticleFilterTopologyStage& topology) {
  const auto frame = recorded.find(kMapSourceLastFrameKey);
  const auto name = recorded.find(kMapSourceLastFrameNameKey);
  if (frame == recorded.end() || name == recorded.end()) return;
  std::int64_t last = -1;
  try {
    last = std::stoll(frame->second);
  } catch (const std::exception&) {
    spdlog::warn("toposlamd: the map's {} is not a frame number ('{}'): reading {} from its first frame",
                 kMapSourceLastFrameKey, frame->second, config.source);
    return;
  }
  if (config.map.source_from_start) {
    spdlog::info("toposlamd: the map holds {} up to frame {} ({}); reading it from its first frame again "
                 "(map.source_from_start)", config.source, last, name->second);
    return;
  }
  const std::optional<std::int64_t> next = source.continueAfter(last, name->second);
  if (!next) return;  // the source said why
  topology.setLastMappedFrame(*next - 1, name->second);
  const std::int64_t total = source.frameCountHint();
  if (total >= 0 && *next >= total)
    spdlog::info("toposlamd: the map holds every frame of {} (up to frame {}, {}): nothing left to map "
                 "(map.source_from_start: true reads it again)", config.source, *next - 1, name->second);
  else
    spdlog::info("toposlamd: continuing {} after frame {} ({}), the last one the map holds: skipping the {} "
                 "frames already mapped (map.source_from_start: true reads it from its first frame)",
                 config.source, *next - 1, name->second, *next);
}

/// What a map made by this run records: mapDecisionSettings (the key table's recorded_in_map keys), the
/// keypoint backend under its older name ("keypoints", what maps before format 4 recorded) and the source.
MapSettings mapSettingsOf(const DaemonConfig& config) {
  MapSettings settings = fingerprintMapSettings(config.fingerprint);
  for (auto& [key, value] : mapDecisionSettings(config)) settings[key] = std::move(value);
  settings[kMapSourceKey] = mapSourceOf(config.source);
  return settings;
}

/// Throws MapStoreError (exit 2) naming the settings that differ unless a map recorded with `recorded` may be
/// continued by this run: the keypoint backend always agrees, the source unless map.resume_other_source,
/// every other recorded setting unless map.resume_other_settings (then each is named in a warning). A map
/// that records none of the settings (made before format 4) cannot be compared: said, and continued.
/// Returns true when the map was made from another source.
bool checkResumable(const MapSettings& recorded, const MapSettings& current, const MapConfig& map,
                    const std::string& name) {
  const MapSettings decision_keys = mapDecisionSettings(DaemonConfig());
  const bool other_source = settingDiffers(recorded, current, kMapSourceKey);
  std::vector<std::string> other_settings, unrecorded;
  for (const auto& [key, value] : decision_keys) {
    if (recorded.count(key) == 0)
      unrecorded.push_back(key);
    else if (settingDiffers(recorded, current, key))
      other_settings.push_back(key + "=" + recorded.at(key) + " (now " + current.at(key) + ")");
  }
  MapSettings compared = current;
  if (map.resume_other_source) compared.erase(kMapSourceKey);
  if (map.resume_other_settings)
    for (const auto& [key, value] : decision_keys) compared.erase(key);
  if (const std::string refusal = MapStore::checkSettings(recorded, compared, name); !refusal.empty()) {
    std::string hint;
    if (other_source && !map.resume_other_source)
      hint += "map.resume_other_source: true or --resume-other-source continues it from this source; ";
    if (!other_settings.empty() && !map.resume_other_settings)
      hint += "map.resume_other_settings: true or --resume-other-settings continues it with this run's settings; ";
    throw MapStoreError(refusal + " (" + hint + "--no-map-load starts a new map)");
  }
  if (other_source)
    spdlog::warn("toposlamd: the map {} was made from {}; continuing it from {} (map.resume_other_source)", name,
                 recorded.at(kMapSourceKey), current.at(kMapSourceKey));
  if (!other_settings.empty()) {
    std::string list;
    for (const std::string& setting : other_settings) list += (list.empty() ? "" : ", ") + setting;
    spdlog::warn("toposlamd: the map {} was made with other settings; continuing it with this run's "
                 "(map.resume_other_settings), the filter's own from the map: {}", name, list);
  }
  if (!unrecorded.empty())
    spdlog::warn("toposlamd: the map {} records {} of the {} settings a map made now records (it was made by an "
                 "older toposlam): they cannot be compared; continuing it with this run's settings", name,
                 unrecorded.size() == decision_keys.size() ? "none" : "not all", decision_keys.size());
  return other_source;
}

}  // namespace

std::string resolveMapPath(const std::string& path) {
  if (path.empty()) return path;
  std::filesystem::path p(path);
  if (p.is_absolute()) return path;
  if (const char* state = std::getenv("STATE_DIRECTORY"); state != nullptr && state[0] != '\0') {
    std::string first(state);
    first = first.substr(0, first.find(':'));  // several StateDirectory= entries are colon-separated
    return (std::filesystem::path(first) / p).string();
  }
  return path;
}

/// map.mode localize: the loaded map is localised in and never changed. Throws ConfigError (exit 2) when
/// there is no map to localise in.
void startLocalizing(const DaemonConfig& config, const std::string& map_path, ParticleFilterTopologyStage& topology) {
  if (topology.observations() == 0)
    throw ConfigError("map.mode is localize but no map with places loads from " + map_path +
                      " (make one first with map.mode: map)");
  topology.startLocalizing(nodeLocalizerConfig(config.similarity, config.map.localize));
  spdlog::info("toposlamd: localising in {} ({} nodes); the map is never changed or saved", map_path,
               topology.topology().nodes.size());
}

int runDaemon(const DaemonConfig& config) {
  const std::vector<int> signals = handledSignalNumbers();
  blockSignals(signals);        // before any thread exists: all inherit it
  ignoreSignals(kWriteSignals);  // EPIPE instead of death on a closed log pipe, EFBIG beyond ulimit -f

  SystemdNotifier notifier;
  SteadyClock clock;
  MapConfig map_config = config.map;
  map_config.path = resolveMapPath(config.map.path);
  const bool localizing = config.map.mode == MapMode::Localize;
  // A map that cannot be saved is found out now, not after a session of mapping (one localised in is never
  // saved).
  if (!localizing) checkMapSavable(map_config.path);
  // Localisation only expects another source than the one the map was made from (a later run).
  map_config.resume_other_source = map_config.resume_other_source || localizing;
  if (localizing && (map_config.path.empty() || !config.map.load_at_start))
    throw ConfigError("map.mode is localize: map.path must name the map to localise in, and map.load_at_start "
                      "be true");
  if (localizing && !std::filesystem::exists(map_config.path) &&
      !std::filesystem::exists(MapStore::previousPath(map_config.path)))
    throw ConfigError("map.mode is localize but there is no map at " + map_config.path +
                      " (make one first with map.mode: map)");

  Assembly parts(config, clock, config.source);
  RecordingFrameSource* recording = startRecording(config.record, parts.source);
  spdlog::info("toposlamd: source {}", parts.source->describe());

  // One writer per map: a second daemon (or `toposlam map`) on the same file is refused here, before
  // anything is loaded or saved. Then the temporary files of saves a kill -9 interrupted are removed.
  std::optional<MapLock> map_lock;
  if (!map_config.path.empty()) {
    map_lock = MapLock::acquire(map_config.path);
    if (const int orphans = MapStore::removeOrphanedTemporaries(map_config.path); orphans > 0)
      spdlog::info("toposlamd: removed {} temporary file(s) of interrupted map saves beside {}", orphans,
                   map_config.path);
  }
  // What the map records (and saves) as made with: every setting that changes what the mapping decides,
  // the keypoint backend and this run's source.
  MapSettings map_settings = mapSettingsOf(config);
  parts.stages.topology().setMapSettings(map_settings);
  FrameSource& named_source = *parts.source;
  parts.stages.topology().nameFramesWith([&named_source](std::int64_t sequence) { return named_source.frameName(sequence); });
  if (config.map.load_at_start && !map_config.path.empty()) {
    // The newest file that loads: the map, else its .prev; a file that does not load is kept aside for a
    // human under a timestamped name (never over an earlier one) and the robot starts from what is left.
    const auto max_bytes = static_cast<std::uint64_t>(config.map.max_mb * 1024.0 * 1024.0);
    RecoveredMap recovered = MapStore::recover(map_config.path, parts.stages.similarity(), max_bytes);
    for (const std::string& problem : recovered.problems) spdlog::error("toposlamd: cannot load a map: {}", problem);
    if (recovered.map) {
      const MapSettings recorded = recovered.map->settings;
      const bool other_source = checkResumable(recorded, map_settings, map_config, recovered.loaded_from.string());
      parts.stages.topology().adoptMap(std::move(*recovered.map));
      // From then on the map records this run's settings, with the filter's own from the map (they came
      // with it), and this source.
      DaemonConfig effective = config;
      effective.topology = parts.stages.topology().filter().config();
      map_settings = mapSettingsOf(effective);
      parts.stages.topology().setMapSettings(map_settings);
      spdlog::info("toposlamd: resumed the map {} ({} places){}", recovered.loaded_from.string(),
                   parts.stages.topology().observations(),
                   recovered.problems.empty() ? "" : ", the newest file that loads");
      if (!other_source && !localizing) continueSource(recorded, config, *parts.source, parts.stages.topology());
    } else if (!recovered.problems.empty() && !localizing) {
      spdlog::error("toposlamd: no map file of {} loads; starting a new map", map_config.path);
    }
  }
  if (localizing) startLocalizing(config, map_config.path, parts.stages.topology());

  const double watchdog_s = config.watchdog.enabled ? notifier.watchdogPeriodSeconds() : 0.0;
  if (!waitForNetwork(config, signals, notifier, watchdog_s, clock)) return 0;

  // Motion input: counted, and fed to the segmentation's MotionGate (docs/segmentation.md, "Motion-aware
  // segmentation"; motion_t.utime and the pipeline's SteadyClock are both CLOCK_MONOTONIC).
  MotionStatusCounters motion_status;
  std::atomic<bool> receiving{true};
  const LcmChannels channels = channelsOf(config.lcm);
  FiedlerSegmentationStage& segmentation_stage = parts.stages.segmentation();
  segmentation_stage.reportMotionTo(&motion_status);
  LcmSubscriber motion(config.lcm.url, channels, {channels.motion}, [&](const ReceivedMessage& m) {
    motion_status.messages.fetch_add(1);
    // Stamped on arrival: the gate refuses a sample whose utime is off this clock (clock_tolerance_s).
    segmentation_stage.addMotion(MotionSample{m.motion_time_s, m.motion_distance_m, m.motion_speed_mps,
                                              m.motion_turn_rate_rps, clock.now()});
  });
  LcmPipelineSink sink(config.lcm.url, channels, config.lcm.jpeg_quality, &motion_status);

  Pipeline pipeline(config.pipeline, map_config, config.watchdog, *parts.source, parts.stages.fingerprint(),
                    parts.stages.segmentation(), parts.stages.topology(), sink, clock);
  if (config.pipeline.queues.overflow == QueueOverflow::Auto)
    spdlog::info("toposlamd: full queues {} (pipeline.queues.overflow auto: {})", toString(pipeline.overflow()),
                 pipeline.overflow() == QueueOverflow::Block
                     ? "the source waits for the pipeline, so every frame is processed"
                     : "the source runs in real time, so the oldest frame is dropped and counted");
  ThreadTable io_threads;
  // Whatever ends this function, the I/O threads are told to end before the table joins them.
  struct EndIoThreads {
    std::atomic<bool>& receiving;
    RecordingFrameSource* recording;
    ~EndIoThreads() {
      receiving.store(false);
      if (recording != nullptr) recording->closeWriter();
    }
  } end_io_threads{receiving, recording};
  io_threads.start(config.pipeline.threads.lcm_receiver, [&] {
    while (receiving.load()) {
      const bool open = motion.handle(200);
      motion_status.malformed.store(motion.malformed());  // dropped by the subscriber, counted in the status
      motion_status.fragments_abandoned.store(motion.fragments_abandoned());  // lost in reassembly (-1: unknown)
      if (!open) break;
    }
  });
  // The recording's writer: nice 10 by default, so encoding and writing frames yield to the stage threads.
  if (recording != nullptr)
    io_threads.start(config.pipeline.threads.recorder, [recording] { recording->runWriter(); });
  pipeline.start();
  notifier.ready();
  notifier.status("running: " + parts.source->describe());
  spdlog::info("toposlamd: running; publishing on {} ({})", config.lcm.url, channels.place);

  // Ping twice per watchdog period; otherwise wake once a second for the status line.
  const double tick_s = watchdog_s > 0 ? std::min(1.0, watchdog_s / 2.0) : 1.0;
  bool stopping = false;
  while (!pipeline.finished()) {
    // Once stopping, look for the end more often so the exit follows the map save closely.
    const int signal = waitForSignal(signals, stopping ? std::min(tick_s, 0.1) : tick_s);
    if (signal != 0 && !isStopSignal(signal)) {
      spdlog::info("toposlamd: {} received: ignored (stop with SIGTERM, SIGINT, SIGHUP or SIGQUIT)", strsignal(signal));
    } else if (signal != 0 && stopping) {
      spdlog::info("toposlamd: {} received while stopping: the map is being saved", strsignal(signal));
    } else if (signal != 0 && !stopping) {
      stopping = true;
      spdlog::info("toposlamd: {} received: finishing the filter step in progress and saving the map",
                   strsignal(signal));
      notifier.stopping();
      notifier.status("stopping: finishing the filter step and saving the map");
      pipeline.requestStop();
    }
    if (watchdog_s > 0 && pipeline.healthy()) notifier.watchdog();
    if (!stopping) {
      // Says when the camera is reconnecting; a stalled stage (no heartbeat while inside its work) is named,
      // since that is also why the watchdog pings stop.
      const std::string stalled = pipeline.stalledStages();
      std::string line = statusLine(pipeline.status());
      // Robot motion, once any has arrived: whether segmentation uses it (docs/segmentation.md).
      if (const std::string motion_line = motionStatusText(motion_status); !motion_line.empty())
        line += "; " + motion_line;
      if (recording != nullptr) line += "; " + recordingStatus(*recording);
      notifier.status(stalled.empty() ? line : "stalled: " + stalled + " without progress (watchdog pings withheld); " + line);
    }
  }
  // The end of the stream (a file or simulator source ran out) is a stop too: systemd hears STOPPING=1
  // before the final map save, as after a signal.
  if (!stopping) {
    notifier.stopping();
    notifier.status("stopping: end of stream; saving the map");
  }
  pipeline.wait();
  receiving.store(false);
  if (recording != nullptr) recording->closeWriter();  // every frame is in: the writer finishes the queue
  io_threads.joinAll();
  if (recording != nullptr) {
    const RecordingStatus r = recording->status();
    spdlog::info("toposlamd: {} into {} ({} frames offered); replay: images:{}?rate=recorded", recordingStatus(*recording),
                 r.folder, r.offered, r.folder);
  }

  const std::string error = pipeline.error();
  const PipelineStatus last = pipeline.status();
  const std::string skipped = skippedFramesText(last.source_skipped_by_reason);  // by reason, "" if none
  spdlog::info("toposlamd: {} frames published, {} dropped, {} places, {} map saves{}", last.frames_published,
               last.frames_dropped, last.places, last.maps_saved, skipped.empty() ? "" : ", " + skipped);
  if (const std::int64_t unsent = notifier.droppedNotifications(); unsent > 0)
    spdlog::warn("toposlamd: {} service notifications found systemd's notify socket full and were dropped", unsent);
  if (!error.empty()) {
    notifier.status("failed: " + error);
    spdlog::error("toposlamd: {}", error);
    return 1;
  }
  return 0;
}

}  // namespace toposlam::daemon
