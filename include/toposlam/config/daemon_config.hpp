// The one validated configuration of toposlamd (and of `toposlam` commands that run the pipeline):
// every stage's config struct (defaults in code, validate() in its module) plus the daemon's own keys,
// loaded once from YAML. Which YAML key lands in which member, with its default, range, unit and help,
// is written once, in the key table (config_keys.hpp); the reader and validate() here are made from it.
// Unknown and repeated keys are refused with their path and line, out-of-range or ill-typed values with
// the key's full dotted name and its allowed range; absent keys keep their defaults. No string look-ups
// happen after loading: stages get their structs by const reference.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "toposlam/config/config_key.hpp"
#include "toposlam/config/config_reader.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/pipeline.hpp"
#include "toposlam/pipeline/stage_assembly.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {


struct LcmSettings {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";  ///< ttl=0: multicast stays on this host
  std::string place_channel = "TOPOSLAM_PLACE";          ///< place estimate, every frame
  std::string place_event_channel = "TOPOSLAM_PLACE_EVENT";  ///< a place's step finished
  std::string topology_channel = "TOPOSLAM_TOPOLOGY";    ///< most probable topology, when it changes
  std::string status_channel = "TOPOSLAM_STATUS";        ///< pipeline status, every status period
  std::string motion_channel = "TOPOSLAM_MOTION";        ///< input: robot motion
  int jpeg_quality = 80;                                 ///< place-event thumbnails, 1 .. 100
  /// Seconds between attempts to open LCM while the host has no route to the multicast group (the
  /// network is not up yet), 0 .. 3600; 0 = no waiting: exit 1 at once.
  double open_retry_s = 2.0;
};

/// record: the frames toposlamd processes, kept for replay (io/recording_frame_source.hpp).
struct RecordSettings {
  /// Parent folder of the recordings ("" = no recording); each run records into a new subfolder named by
  /// its UTC start time. Relative: against $STATE_DIRECTORY (like map.path), else the working directory.
  std::string dir;
  double max_mb = 1024;        ///< bound on all recordings under `dir` together, 1 .. 10000000 MB
  std::string format = "jpg";  ///< jpg or png (lossless, about 5x larger)
  int jpeg_quality = 95;       ///< 1 .. 100 (toposlam capture --record's too)
  int queue_frames = 16;       ///< frames waiting for the writer before the oldest is dropped, 1 .. 1024
};

/// The stages' settings (fingerprint, similarity, segmentation, topology: StageSettings, the members
/// StageAssembly builds the stages from) and the daemon's own.
struct DaemonConfig : StageSettings {
  /// Method preset (method_preset.hpp): "default" (measured on real frames) or "thesis"; it sets every
  /// stage's settings before the other keys are read.
  std::string preset = "default";
  /// Frame source URI (see io/source_factory.hpp): images:PATH, video:FILE, sim:WORLD?..., v4l2:/dev/videoN.
  std::string source = "sim:office?route=loop2";
  LcmSettings lcm;
  RecordSettings record;
  /// log_level: trace, debug, info, warn or error (toposlamd --log-level overrides it).
  std::string log_level = "info";
  /// map.*: the Pipeline saves the map (path, save_period_s); toposlamd loads it at start (the rest).
  MapConfig map;
  WatchdogConfig watchdog;  ///< watchdog.*: the Pipeline's heartbeat, toposlamd's systemd pings
  PipelineConfig pipeline;  ///< pipeline.*: queues, threads, budgets

  DaemonConfig();
  /// "" or "<full.dotted.key>: <problem, allowed range>": every key's range and cross-key constraint of
  /// the key table, then every stage's own validate() as a backstop.
  std::string validate() const;
};

/// Sets `config.preset` and every stage's settings from the method preset `name` (method_preset.hpp).
/// Throws std::invalid_argument for an unknown name.
void applyMethodPreset(const std::string& name, DaemonConfig& config);

/// Parses YAML text onto the defaults. `origin` names the text in messages (a file name).
/// Throws ConfigError on syntax errors, unknown keys, wrong types and out-of-range values.
/// `preset` (not ""): the command line's preset, applied instead of the text's own `preset:` key (before the
/// text's other keys, as the text's own preset would be).
DaemonConfig parseDaemonConfig(const std::string& yaml_text, const std::string& origin = "config",
                               const std::string& preset = "");
/// Reads and parses a file; ConfigError if it cannot be read, is a folder or is over kMaxConfigBytes.
/// A repeated key or a second YAML document is refused (parseDaemonConfig).
DaemonConfig loadDaemonConfig(const std::string& path, const std::string& preset = "");

/// Sets the key at `path` (a key of the table) from its text as written on a command line, e.g.
/// ("map.save_period_s", "30"); ConfigError naming the key if the text is not a value of its kind.
/// Ranges are checked by validate().
void setConfigValue(DaemonConfig& config, const std::string& path, const std::string& text);

/// The override of `--set KEY=VALUE` (`assignment` is "KEY=VALUE"); ConfigError "command line: --set TEXT:
/// ..." when it
/// has no '=' or KEY is no key of the table.
ConfigOverride parseSetOverride(const std::string& assignment);

/// The one way a command line makes its config (toposlamd and the offline commands alike): the file at
/// `path` ("" = the built-in defaults), then `overrides` in order, then validate(). A `preset` override is
/// applied first, in place of the file's own `preset:` (a preset sets every stage; the other keys, of the
/// file and of the command line, override it). ConfigError "<file>: <key>: <problem>", "command line:
/// <given_as>: <key>: <problem>" for a value of the wrong kind or out of the key's range, "command line:
/// <key>: <problem>" for a cross-key constraint.
DaemonConfig commandLineConfig(const std::string& path, const std::vector<ConfigOverride>& overrides);

}  // namespace toposlam
