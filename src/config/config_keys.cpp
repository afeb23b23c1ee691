// The key table of toposlamd's config (see config_keys.hpp): the one place a key, its default, range,
// unit and help are written. The defaults are those of a default-constructed DaemonConfig (stage structs
// plus the "default" method preset); test_config_keys checks every one mechanically.
#include "toposlam/config/config_keys.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "toposlam/config/daemon_config.hpp"
#include "toposlam/config/method_preset.hpp"

namespace toposlam {

namespace {

// The member a key lands in, for const and non-const configs alike.
#define AT(member) [](auto& c) -> auto& { return c.member; }

// Range ends in cross-check messages.
std::string rangeNumber(double v) { return configRangeNumber(v); }

// The table is built by static members of a ConfigKeyBuilders<DaemonConfig>, so integer(...), real(...) ... name
// the builders of config_key.hpp.
struct DaemonKeyTable : ConfigKeyBuilders<DaemonConfig> {
  static void addThread(std::vector<ConfigKey>& keys, const std::string& thread, ThreadSettings PipelineThreads::*member,
                        const std::string& def_name, int def_nice = 0);
  static std::vector<ConfigKey> makeKeys();
};

// The five keys of one pipeline thread.
void DaemonKeyTable::addThread(std::vector<ConfigKey>& keys, const std::string& thread,
                               ThreadSettings PipelineThreads::*member, const std::string& def_name, int def_nice) {
  const std::string p = "pipeline.threads." + thread + ".";
  const auto at = [member](auto& c) -> auto& { return c.pipeline.threads.*member; };
  keys.push_back(text(p + "name", [at](auto& c) -> auto& { return at(c).name; }, def_name, 1, 15,
                      "thread name (Linux limit: 15 characters)"));
  keys.push_back(integer(p + "cpu", [at](auto& c) -> auto& { return at(c).cpu; }, -1, -1, 1023, "",
                         "CPU to pin the thread to").withNote("-1 = no pinning"));
  keys.push_back(choice(p + "policy", [at](auto& c) -> auto& { return at(c).policy; }, SchedulingPolicy::Other,
                        {{"other", SchedulingPolicy::Other}, {"fifo", SchedulingPolicy::Fifo}},
                        "scheduling policy"));
  keys.push_back(integer(p + "priority", [at](auto& c) -> auto& { return at(c).priority; }, 0, 0, 99, "",
                         "SCHED_FIFO priority; one that cannot be set (no CAP_SYS_NICE / LimitRTPRIO) is logged, "
                         "not fatal")
                     .withNote("1 .. 99 with policy fifo, 0 with other")
                     .withCrossCheck([at](const DaemonConfig& c) -> std::string {
                       const ThreadSettings& t = at(c);
                       if (t.policy == SchedulingPolicy::Fifo && (t.priority < 1 || t.priority > 99))
                         return std::to_string(t.priority) + " is out of range for policy fifo, allowed 1 .. 99";
                       if (t.policy == SchedulingPolicy::Other && t.priority != 0)
                         return std::to_string(t.priority) + " is out of range for policy other, allowed 0";
                       return "";
                     }));
  keys.push_back(integer(p + "nice", [at](auto& c) -> auto& { return at(c).nice; }, def_nice, -20, 19, "",
                         "nice value with policy other (0 = leave as is)"));
}

std::vector<ConfigKey> DaemonKeyTable::makeKeys() {
  const long long kMaxSeed = std::numeric_limits<long long>::max();
  std::vector<ConfigKey> k;
  // Top level.
  k.push_back(choice("preset", AT(preset), std::string("default"), methodPresetNames(),
                     "method preset: default (measured on real frames: docs/matching.md, docs/topology.md) or "
                     "thesis (the published method exactly: 100 keypoints, the n-gram similarity with equal "
                     "weights, a 25-frame window, the similarity itself as the filter's likelihood). It sets "
                     "every stage's settings (fingerprint, similarity, segmentation, topology) first; the keys "
                     "below override them"));
  k.back().set = [](DaemonConfig& c, const ConfigValue& v) { applyMethodPreset(std::get<std::string>(v), c); };
  k.push_back(text("source", AT(source), "sim:office?route=loop2", 1, 4096,
                   "frame source URI: images:PATH_OR_GLOB (natural order), video:FILE, "
                   "sim:WORLD?route=R&fps=F&size=WxH&seed=S, v4l2:/dev/videoN?size=WxH&fps=F&format=F, "
                   "libcamera:ID; files take ?rate=FPS to play in real time. While a camera is absent the "
                   "service waits for it (status \"camera reconnecting\")")
                  .withOption("--source"));
  k.back().example = "sim:office?route=loop2 or v4l2:/dev/video0";
  k.push_back(choice("log_level", AT(log_level), std::string("info"), {"trace", "debug", "info", "warn", "error"},
                     "log level. Logs go to stderr; under systemd they carry journal priorities, so "
                     "`journalctl -u toposlamd -p warning` shows warnings and errors")
                  .withOption("--log-level"));
  // LCM.
  k.push_back(text("lcm.url", AT(lcm.url), "udpm://239.255.76.67:7667?ttl=0", 1, 4096,
                   "LCM provider URL (udpm://, mpudpm://, memq://, file:// or tcpq://). ttl=0 keeps multicast "
                   "on this host; ttl=1 reaches the robot's LAN")
                  .withOption("--lcm-url")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    static const char* const kProviders[] = {"udpm://", "mpudpm://", "memq://", "file://", "tcpq://"};
                    for (const char* p : kProviders)
                      if (c.lcm.url.rfind(p, 0) == 0) return "";
                    return "'" + c.lcm.url +
                           "' is not an LCM URL, expected udpm://, mpudpm://, memq://, file:// or tcpq://";
                  }));
  k.back().example = "udpm://239.255.76.67:7667?ttl=0";
  k.push_back(text("lcm.channels.place", AT(lcm.place_channel), "TOPOSLAM_PLACE", 1, 255,
                   "out: place estimate, every frame (toposlam_lcm.place_t)"));
  k.push_back(text("lcm.channels.place_event", AT(lcm.place_event_channel), "TOPOSLAM_PLACE_EVENT", 1, 255,
                   "out: a place was closed and mapped (place_event_t, with a JPEG thumbnail)"));
  k.push_back(text("lcm.channels.topology", AT(lcm.topology_channel), "TOPOSLAM_TOPOLOGY", 1, 255,
                   "out: most probable topology, when it changes (topology_t)"));
  k.push_back(text("lcm.channels.status", AT(lcm.status_channel), "TOPOSLAM_STATUS", 1, 255,
                   "out: pipeline status, every pipeline.status_period_s (status_t)"));
  k.push_back(text("lcm.channels.motion", AT(lcm.motion_channel), "TOPOSLAM_MOTION", 1, 255,
                   "in: robot motion (motion_t), counted in the status"));
  k.push_back(integer("lcm.jpeg_quality", AT(lcm.jpeg_quality), 80, 1, 100, "", "place-event thumbnail JPEG quality"));
  k.push_back(real("lcm.open_retry_s", AT(lcm.open_retry_s), 2.0, 0, 3600, "seconds",
                   "no route to the multicast group yet (network not up): try again every this many seconds, "
                   "status \"waiting for the network\"")
                  .withNote("0 = exit 1 at once"));
  // Recording (RecordSettings; docs/deploy.md section 5).
  k.push_back(text("record.dir", AT(record.dir), "", 0, 4096,
                   "record the frames processed into a new subfolder (its UTC start time) of this folder, for "
                   "images:DIR/<subfolder>?rate=recorded. Relative paths resolve like map.path. \"\" = no recording")
                  .withOption("--record"));
  k.push_back(real("record.max_mb", AT(record.max_mb), 1024, 1, 1e7, "MB",
                   "bound on all recordings under record.dir together; recording stops there, mapping goes on"));
  k.push_back(choice("record.format", AT(record.format), std::string("jpg"), std::vector<std::string>{"jpg", "png"},
                     "jpg, or png (lossless, about 5x larger)"));
  k.push_back(integer("record.jpeg_quality", AT(record.jpeg_quality), 95, 1, 100, "", "JPEG quality of the recording"));
  k.push_back(integer("record.queue_frames", AT(record.queue_frames), 16, 1, 1024, "frames",
                      "frames waiting for the writer before the oldest is dropped (counted)"));
  // Map.
  k.push_back(choice("map.mode", AT(map.mode), MapMode::Map, {{"map", MapMode::Map}, {"localize", MapMode::Localize}},
                     "map (build the map, resuming it from map.path) or localize (localisation only: load the "
                     "map at map.path, which must exist, and never change it; every frame gets the node it is "
                     "in, or \"not a known node\"; docs/daemon.md, \"Localisation only\")")
                  .withFlagOption("--localize-only", "localize"));
  k.push_back(real("map.localize.min_probability", AT(map.localize.min_probability), 0.5, 0, 1, "",
                   "localisation only: a frame whose best node's belief is under this answers \"not a known "
                   "node\" (node -1)"));
  k.push_back(real("map.localize.jump_weight", AT(map.localize.jump_weight), 0.01, 0, 1, "",
                   "localisation only: weight of moving to any node, not only along the map's edges, between two "
                   "frames (how fast a robot carried elsewhere is found again)"));
  k.push_back(text("map.path", AT(map.path), "map.tsm", 0, 4096,
                   "the map file (MapStore format, docs/topology.md). Relative paths resolve against "
                   "$STATE_DIRECTORY (systemd StateDirectory=toposlam: /var/lib/toposlam), else the working "
                   "directory. \"\" = never saved")
                  .withOption("--map"));
  k.push_back(flag("map.load_at_start", AT(map.load_at_start), true,
                   "resume from the map if it exists; a damaged file is moved to *.damaged-<UTC time> and "
                   "map.tsm.prev is loaded instead")
                  .withOption("--no-map-load", false));
  k.push_back(flag("map.resume_other_source", AT(map.resume_other_source), false,
                   "a map records its source (v4l2:/dev/video0, sim:office, ...); one made from another source "
                   "is refused (exit 2) unless this is true")
                  .withOption("--resume-other-source", true));
  k.push_back(flag("map.resume_other_settings", AT(map.resume_other_settings), false,
                   "a map records every setting that changes what the mapping decides (fingerprint, similarity, "
                   "segmentation, topology); one made with other values is refused (exit 2, naming them) unless "
                   "this is true. The keypoint backend is never waived; the filter's own settings (particles, "
                   "likelihood, ...) always come from the map")
                  .withOption("--resume-other-settings", true));
  k.push_back(flag("map.source_from_start", AT(map.source_from_start), false,
                   "a map made from a folder of images records the last frame it holds, and a restart from "
                   "the same folder continues after that frame (each frame is mapped once); true reads the "
                   "folder from its first frame again")
                  .withOption("--source-from-start", true));
  k.push_back(real("map.save_period_s", AT(map.save_period_s), 60.0, 0, 86400, "seconds",
                   "seconds between periodic saves")
                  .withNote("0 = only at stop, else at least 1")
                  .withOption("--save-period")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    const double v = c.map.save_period_s;
                    if (v == 0.0 || v >= 1.0) return "";
                    return rangeNumber(v) + " is out of range, allowed 0 (only at stop) or [1, 86400] seconds";
                  }));
  k.push_back(real("map.max_mb", AT(map.max_mb), 256.0, 1, 65536, "MB",
                   "a bigger map file is refused unread (the daemon does not start)"));
  // Watchdog.
  k.push_back(flag("watchdog.enabled", AT(watchdog.enabled), true,
                   "ping systemd (WatchdogSec= in the unit) while the pipeline is healthy"));
  k.push_back(real("watchdog.heartbeat_timeout_s", AT(watchdog.heartbeat_timeout_s), 5.0, 0.5, 600, "seconds",
                   "a stage thread silent this long stops the pings"));
  // Pipeline.
  k.push_back(integer("pipeline.queues.frames", AT(pipeline.queues.frames), 2, 1, 1024, "frames",
                      "capture -> fingerprint (frames hold camera buffers: keep small)"));
  k.push_back(integer("pipeline.queues.fingerprints", AT(pipeline.queues.fingerprints), 8, 1, 1024, "frames",
                      "fingerprint -> segmentation"));
  k.push_back(integer("pipeline.queues.segmented", AT(pipeline.queues.segmented), 8, 1, 1024, "frames",
                      "segmentation -> topology"));
  k.push_back(integer("pipeline.queues.results", AT(pipeline.queues.results), 16, 1, 1024, "frames",
                      "topology -> publisher"));
  k.push_back(choice("pipeline.queues.overflow", AT(pipeline.queues.overflow), QueueOverflow::Auto,
                     {{"auto", QueueOverflow::Auto}, {"drop_oldest", QueueOverflow::DropOldest},
                      {"block", QueueOverflow::Block}},
                     "auto (drop_oldest for a camera or a file played with ?rate=, block for files and the "
                     "simulator read as fast as the pipeline goes), drop_oldest (real time: the oldest frame is "
                     "dropped and counted) or block (lossless replay)")
                  .withOption("--overflow"));
  addThread(k, "capture", &PipelineThreads::capture, "tsl-capture");
  addThread(k, "fingerprint", &PipelineThreads::fingerprint, "tsl-fingerprint");
  addThread(k, "segmentation", &PipelineThreads::segmentation, "tsl-segment");
  addThread(k, "topology", &PipelineThreads::topology, "tsl-topology");
  addThread(k, "publisher", &PipelineThreads::publisher, "tsl-publish");
  addThread(k, "map_writer", &PipelineThreads::map_writer, "tsl-mapsave");
  addThread(k, "lcm_receiver", &PipelineThreads::lcm_receiver, "tsl-lcm-rx");
  addThread(k, "recorder", &PipelineThreads::recorder, "tsl-record", 10);
  k.push_back(real("pipeline.filter_budget_ms", AT(pipeline.filter_budget_ms), 5.0, 0.1, 1000, "milliseconds",
                   "topology filter work per frame"));
  k.push_back(real("pipeline.status_period_s", AT(pipeline.status_period_s), 1.0, 0.1, 60, "seconds",
                   "status message period"));
  // The fingerprint stage makes the thumbnails; the key keeps its path from when the Pipeline made them.
  k.push_back(integer("pipeline.thumbnail_width", AT(fingerprint_stage.thumbnail_width), 160, 16, 1280,
                      "pixels", "place-event thumbnail width (the height keeps the aspect)"));
  k.push_back(integer("pipeline.opencv_threads", AT(pipeline.opencv_threads), 1, 0, 64, "threads",
                      "OpenCV's own pool, set at start (1: each OpenCV call runs on its stage thread; the thread "
                      "table gives out the parallelism, docs/performance.md)"));
  // Fingerprint (VpackConfig, its pool size beside it).
  k.push_back(integer("fingerprint.workers", AT(fingerprint_stage.workers), 2, 1, 64, "threads",
                      "WorkerPool threads for the per-subregion work, incl. the fingerprint thread"));
  k.push_back(real("fingerprint.edges.opening_height_fraction", AT(fingerprint.edges.opening_height_fraction), 0.2, 0,
                   1, "", "vertical opening kernel / image height (thesis: 1/5)")
                  .exclusive(true, false));
  k.push_back(integer("fingerprint.edges.dilation_width", AT(fingerprint.edges.dilation_width), 3, 1, 31, "pixels",
                      "horizontal dilation (thesis: 3)"));
  k.push_back(real("fingerprint.edges.mean_factor", AT(fingerprint.edges.mean_factor), 5.0, 0, 100, "",
                   "keep columns above this x the mean response (thesis: 5)")
                  .exclusive(true, false));
  k.push_back(real("fingerprint.edges.min_separation_fraction", AT(fingerprint.edges.min_separation_fraction), 0.05, 0,
                   0.5, "", "non-maximum suppression half-neighbourhood / image width (thesis: 5 %)")
                  .exclusive(true, false));
  k.push_back(real("fingerprint.histogram.achromatic_chroma", AT(fingerprint.histogram.achromatic_chroma), 0.125, 0,
                   1, "", "chroma at or below this is grey (thesis: 12.5 %)")
                  .exclusive(false, true));
  k.push_back(real("fingerprint.histogram.min_lightness", AT(fingerprint.histogram.min_lightness), 0.0, 0, 1, "",
                   "ignore darker pixels"));
  k.push_back(real("fingerprint.histogram.max_lightness", AT(fingerprint.histogram.max_lightness), 1.0, 0, 1, "",
                   "ignore brighter pixels")
                  .withNote("and > min_lightness")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    const HclHistogramConfig& h = c.fingerprint.histogram;
                    if (h.max_lightness > h.min_lightness) return "";
                    return rangeNumber(h.max_lightness) + " is out of range, allowed (min_lightness = " +
                           rangeNumber(h.min_lightness) + ", 1]";
                  }));
  k.push_back(choice("fingerprint.keypoints.backend", AT(fingerprint.keypoints.backend), KeypointBackend::Orb,
                     {{"orb", KeypointBackend::Orb},
                      {"sift", KeypointBackend::Sift},
                      {"brisk", KeypointBackend::Brisk},
                      {"akaze", KeypointBackend::Akaze}},
                     "keypoint detector and descriptor"));
  k.push_back(integer("fingerprint.keypoints.max_keypoints", AT(fingerprint.keypoints.max_keypoints), 100, 0, 10000,
                      "", "keypoints per frame (thesis: 100)"));
  k.push_back(integer("fingerprint.keypoints.threshold_iterations", AT(fingerprint.keypoints.threshold_iterations), 8,
                      0, 64, "", "response threshold adjustments per subregion"));
  k.push_back(integer("fingerprint.keypoints.candidate_limit", AT(fingerprint.keypoints.candidate_limit), 1000, 0,
                      100000, "", "the detector's own cap on candidates before selection")
                  .withNote("and >= max_keypoints")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    const KeypointConfig& kp = c.fingerprint.keypoints;
                    if (kp.candidate_limit >= kp.max_keypoints) return "";
                    return std::to_string(kp.candidate_limit) + " is out of range, allowed max_keypoints (" +
                           std::to_string(kp.max_keypoints) + ") .. 100000";
                  }));
  k.push_back(integer("fingerprint.keypoints.orb_levels", AT(fingerprint.keypoints.orb_levels), 6, 1, 16, "",
                      "ORB pyramid levels (fewer is faster)"));
  k.push_back(integer("fingerprint.keypoints.orb_fast_threshold", AT(fingerprint.keypoints.orb_fast_threshold), 12, 1,
                      254, "", "ORB FAST floor; low so the subregions have candidates to choose from"));
  k.push_back(integer("fingerprint.min_image_width", AT(fingerprint.min_image_width), 16, 4, 100000, "pixels",
                      "smaller frames are skipped (counted)"));
  k.push_back(integer("fingerprint.min_image_height", AT(fingerprint.min_image_height), 16, 4, 100000, "pixels",
                      "smaller frames are skipped (counted)"));
  // Similarity (NgramSimilarityConfig).
  k.push_back(real("similarity.matcher.max_hellinger_distance", AT(similarity.matcher.max_hellinger_distance), 0.3, 0,
                   1, "", "histograms match at most this normalised Hellinger distance apart (thesis: 0.3)")
                  .exclusive(true, false));
  k.push_back(real("similarity.matcher.max_binary_distance_fraction",
                   AT(similarity.matcher.max_binary_distance_fraction), 0.25, 0, 1, "",
                   "binary descriptors: most Hamming distance of a kept match, as a fraction of the bits")
                  .exclusive(true, false)
                  .withNote("1 disables the test"));
  k.push_back(real("similarity.matcher.max_float_distance", AT(similarity.matcher.max_float_distance), 0.0, 0, 1e6, "",
                   "float descriptors (SIFT): most L2 distance of a kept match")
                  .withNote("0 disables the test"));
  k.push_back(real("similarity.matcher.ratio_test", AT(similarity.matcher.ratio_test), 0.8, 0, 1, "",
                   "Lowe's ratio test: kept when best <= this x second best")
                  .exclusive(true, false)
                  .withNote("1 disables the test"));
  k.push_back(flag("similarity.matcher.mutual_check", AT(similarity.matcher.mutual_check), true,
                   "keep a match only when it is mutual"));
  k.push_back(real("similarity.matcher.max_angle_difference_deg", AT(similarity.matcher.max_angle_difference_deg), 25,
                   0, 180, "degrees", "orientation check: most difference of the two keypoints' orientations")
                  .withNote("0 disables the test"));
  k.push_back(real("similarity.histogram_weight", AT(similarity.histogram_weight), 0.05, 0, 1, "",
                   "weight of the histogram part; the keypoint part gets 1 - this"));
  k.push_back(flag("similarity.histogram_gate", AT(similarity.histogram_gate), false,
                   "histograms scale the keypoint part instead of adding to it"));
  k.push_back(flag("similarity.histogram_only_fallback", AT(similarity.histogram_only_fallback), false,
                   "a reference without keypoints is scored by its histograms alone"));
  k.push_back(choice("similarity.keypoint_scoring", AT(similarity.keypoint_scoring), KeypointScoring::VerifiedMatches,
                     {{"possible-ngrams", KeypointScoring::PossibleNgrams},
                      {"verified-matches", KeypointScoring::VerifiedMatches}},
                     "how the keypoint part is scored (docs/matching.md)"));
  // Segmentation (FiedlerSegmenterConfig, MotionGateConfig).
  k.push_back(real("segmentation.window_s", AT(segmentation.window_s), 6.0, 0, 3600, "seconds",
                   "sliding window in seconds, from frame timestamps")
                  .withNote("0 = `window` frames"));
  k.push_back(integer("segmentation.window", AT(segmentation.window), 100, 3, 1000, "frames",
                      "frames in the window with window_s 0, else the most the window holds"));
  k.push_back(integer("segmentation.min_window_frames", AT(segmentation.min_window_frames), 5, 3, 1000, "frames",
                      "fewest frames a window in seconds (or metres) keeps")
                  .withNote("and <= window")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    if (c.segmentation.min_window_frames <= c.segmentation.window) return "";
                    return std::to_string(c.segmentation.min_window_frames) + " is out of range, allowed 3 .. window (" +
                           std::to_string(c.segmentation.window) + ") frames";
                  }));
  k.push_back(real("segmentation.window_m", AT(segmentation.window_m), 0.0, 0, 1000, "metres",
                   "with robot motion known (TOPOSLAM_MOTION): the window spans this much travel instead of "
                   "window_s (thesis 1.5 .. 1.75; 3 measured best on the simulated office, docs/segmentation.md)")
                  .withNote("0 = off: no window in distance"));
  k.push_back(real("segmentation.min_frame_spacing_m", AT(segmentation.min_frame_spacing_m), 0.09, 0, 100, "metres",
                   "with motion and window_m > 0: leave out a frame closer than this to the last one added, in "
                   "travel and in heading, so a slow stretch does not cut extra places")
                  .withNote("0 = off"));
  k.push_back(real("segmentation.min_frame_spacing_rad", AT(segmentation.min_frame_spacing_rad), 0.03, 0, 10, "rad",
                   "the heading part of min_frame_spacing_m"));
  k.push_back(real("segmentation.similarity_floor", AT(segmentation.similarity_floor), 0.0, 0, 1, "",
                   "subtracted from every similarity before it enters the affinity matrix (clamped at 0), so "
                   "frames of different places that still match by colour become unlinked")
                  .exclusive(false, true));
  k.push_back(real("segmentation.motion.standing_speed_mps", AT(segmentation_stage.motion.standing_speed_mps), 0.05, 0, 10,
                   "m/s", "slower than this counts as standing"));
  k.push_back(real("segmentation.motion.standing_turn_rate_rps", AT(segmentation_stage.motion.standing_turn_rate_rps), 0.1,
                   0, 100, "rad/s", "... unless turning faster than this"));
  k.push_back(real("segmentation.motion.standing_after_s", AT(segmentation_stage.motion.standing_after_s), 1.0, 0, 3600,
                   "seconds", "standing once slow for this long"));
  k.push_back(real("segmentation.motion.timeout_s", AT(segmentation_stage.motion.timeout_s), 1.0, 0, 3600, "seconds",
                   "motion is known while the newest sample is at most this old")
                  .exclusive(true, false));
  k.push_back(real("segmentation.motion.clock_tolerance_s", AT(segmentation_stage.motion.clock_tolerance_s), 1.0, 0,
                   3600, "seconds",
                   "a sample stamped further than this from the receiver's clock (CLOCK_MONOTONIC) is refused and "
                   "counted, and never becomes the reference")
                  .exclusive(true, false));
  k.push_back(real("segmentation.motion.max_speed_mps", AT(segmentation_stage.motion.max_speed_mps), 5.0, 0, 1000,
                   "m/s",
                   "a faster sample, or a distance increment longer than this speed allows, cannot be the robot: "
                   "refused and counted")
                  .exclusive(true, false));
  k.push_back(real("segmentation.motion.max_turn_rate_rps", AT(segmentation_stage.motion.max_turn_rate_rps), 10.0, 0,
                   1000, "rad/s", "a sample turning faster cannot be the robot: refused and counted")
                  .exclusive(true, false));
  k.push_back(real("segmentation.valley.gamma", AT(segmentation.valley.gamma), 0.5, 0, 2, "",
                   "peak height on the lambda2 scale (thesis: 0.5)")
                  .withNote("and <= window / (window - 1)")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    const double max = maxFiedlerValue(c.segmentation.window);
                    if (c.segmentation.valley.gamma <= max) return "";
                    return rangeNumber(c.segmentation.valley.gamma) +
                           " is out of range, allowed [0, window / (window - 1) = " + rangeNumber(max) + "]";
                  }));
  k.push_back(real("segmentation.valley.delta", AT(segmentation.valley.delta), 0.30, 0, 2, "",
                   "rise and fall between peak and valley")
                  .withNote("and <= gamma")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    if (c.segmentation.valley.delta <= c.segmentation.valley.gamma) return "";
                    return rangeNumber(c.segmentation.valley.delta) + " is out of range, allowed [0, gamma = " +
                           rangeNumber(c.segmentation.valley.gamma) + "]";
                  }));
  k.push_back(integer("segmentation.min_keypoints", AT(segmentation.min_keypoints), 15, 0, 10000, "",
                      "places whose representative has fewer keypoints are dropped (thesis: 15)"));
  k.push_back(choice("segmentation.cut_placement", AT(segmentation.cut_placement), CutPlacement::WindowSplit,
                     {{"window-split", CutPlacement::WindowSplit}, {"valley-frame", CutPlacement::ValleyFrame}},
                     "where a place ends: the best split of the valley's window, or the valley frame (thesis)"));
  k.push_back(real("segmentation.doorway_shift_s", AT(segmentation.doorway_shift_s), 7.0, 0, 60, "seconds",
                   "a border moves to the doorway passage nearest it (predicted from the vertical edges) when one is "
                   "at most this far (0 = off, the thesis)"));
  k.push_back(flag("segmentation.doorway_borders", AT(segmentation.doorway_borders), true,
                   "with doorway_shift_s > 0 and window_m 0: a doorway passage makes a border of its own, and a second "
                   "border for the passage a place began at is dropped (docs/segmentation.md, \"Borders at doorways\")"));
  k.push_back(choice("segmentation.representative", AT(segmentation.representative), RepresentativeChoice::WindowDegree,
                     {{"window-degree", RepresentativeChoice::WindowDegree},
                      {"place-medoid", RepresentativeChoice::PlaceMedoid}},
                     "a place's representative: the window frame of largest degree (thesis), or the sampled "
                     "frame most like the place's others"));
  k.push_back(real("segmentation.representative_interval_s", AT(segmentation.representative_interval_s), 0.5, 0, 3600,
                   "seconds", "place-medoid and place_samples: the place's frames are sampled at most this often "
                   "(0 = every frame)"));
  k.push_back(integer("segmentation.place_samples", AT(segmentation.place_samples), 3, 0,
                      FiedlerSegmenterConfig::kMaxQuerySamples, "",
                      "other frames of a closed place that the relative likelihood compares with the stored places "
                      "besides its representative (0 = the representative alone, the thesis)"));
  k.push_back(integer("segmentation.place_views", AT(segmentation.place_views), 7, 0,
                      FiedlerSegmenterConfig::kMaxQuerySamples, "",
                      "other frames of a closed place the map keeps as its views, spread over the place, for "
                      "localisation only (map.mode: localize); they change no mapping decision. Each costs about "
                      "5 kB per place in memory and in the map file (0 = the representative alone, the thesis)"));
  // Topology (TopologyFilterConfig, the stage's slicing beside it).
  k.push_back(integer("topology.particles", AT(topology.particles), 500, 1, 1000000, "",
                      "particles over topologies (thesis: 500)"));
  k.push_back(choice("topology.likelihood", AT(topology.likelihood), LikelihoodModel::Relative,
                     {{"relative", LikelihoodModel::Relative}, {"absolute", LikelihoodModel::Absolute}},
                     "relative (per query, docs/topology.md) or absolute (the similarity itself, thesis)"));
  k.push_back(real("topology.relative_slope", AT(topology.relative_slope), 2.0, 0, 100, "",
                   "relative likelihood: logistic slope per z unit")
                  .exclusive(true, false));
  k.push_back(real("topology.relative_offset", AT(topology.relative_offset), 4.25, -10, 10, "",
                   "relative likelihood: z (leave-one-out, among the stored representatives) at likelihood 1/2"));
  k.push_back(real("topology.relative_sigma_floor", AT(topology.relative_sigma_floor), 0.02, 0, 1, "",
                   "relative likelihood: smallest spread of the other similarities")
                  .exclusive(true, false));
  k.push_back(flag("topology.new_node_entropy", AT(topology.new_node_entropy), false,
                   "a new node's likelihood is eta (1 - max L), eta the normalised entropy of eq. 5.7 (thesis); "
                   "false: 1 - max L (docs/topology.md, \"The new node's likelihood\")"));
  k.push_back(real("topology.alpha", AT(topology.alpha), 15.0, 0, 1e6, "", "expected number of places (thesis: 15)")
                  .exclusive(true, false));
  k.push_back(real("topology.new_node_probability", AT(topology.new_node_probability), 0.02, 0, 1, "",
                   "probability of a new node from a known one (thesis: 0.05; docs/topology.md, \"Look-alike rooms\")")
                  .exclusive(true, true));
  k.push_back(real("topology.new_node_likelihood_floor", AT(topology.new_node_likelihood_floor), 0.01, 0, 1, "",
                   "smallest likelihood of a new node, the chance a new place looks like a stored one (thesis: 0)")
                  .exclusive(false, true));
  k.push_back(real("topology.gamma_shape", AT(topology.gamma_shape), 5.0, 0, 1000, "",
                   "successor gamma pdf shape (5 and scale 0.4 give staying 0.33, docs/topology.md)")
                  .exclusive(true, false));
  k.push_back(real("topology.gamma_scale", AT(topology.gamma_scale), 0.4, 0, 100, "",
                   "successor gamma pdf scale")
                  .exclusive(true, false));
  k.push_back(integer("topology.max_successors", AT(topology.max_successors), 5, 1, kTopologyMaxSuccessors, "",
                      "successors proposed from a known node"));
  k.push_back(integer("topology.max_representatives_per_node", AT(topology.max_representatives_per_node), 8, 1,
                      kTopologyMaxRepresentatives, "", "representatives kept per node and particle, oldest dropped"));
  k.push_back(flag("topology.forbid_return_to_previous", AT(topology.forbid_return_to_previous), false,
                   "also drop the node visited just before the current one from the successor candidates"));
  k.push_back(integer("topology.seed", AT(topology.seed), 1, 0, kMaxSeed, "",
                      "seed of the filter's random generator (runs replay bit for bit)"));
  // Sequence evidence (SequenceEvidenceConfig; docs/topology.md "Sequence evidence in the filter").
  k.push_back(real("topology.sequence_evidence.weight", AT(sequence_evidence.weight), 0.0, 0, 1, "",
                   "likelihood of an earlier place every keyframe of a new place detects into (0 = off, the thesis; "
                   "chosen leave-one-set-out: real look-alike floors close wrongly with it, docs/results.md)"));
  k.push_back(flag("topology.sequence_evidence.frame_revisits", AT(sequence_evidence.frame_revisits), true,
                   "run the sequence detector for every frame and publish its answer in place_t (match_frame, "
                   "match_node: the node the robot is back in); the thesis preset has it off"));
  k.push_back(real("topology.sequence_evidence.min_share", AT(sequence_evidence.min_share), 0.8, 0, 1, "",
                   "share of a new place's keyframes an earlier place needs before it gets evidence"));
  k.push_back(real("topology.sequence_evidence.min_score", AT(sequence_evidence.min_score), 2.0, 0, 1e6, "",
                   "detection score (its noise's standard deviations) a frame's match needs to be published, and a "
                   "keyframe's evidence to count"));
  k.push_back(real("topology.sequence_evidence.min_margin", AT(sequence_evidence.min_margin), 0.5, 0, 1e6, "",
                   "how far (its noise's standard deviations) a published match's run must stand out from every other "
                   "run: a building that repeats gives several runs alike (places published as one count as one)"));
  k.push_back(real("topology.sequence_evidence.distinct_s", AT(sequence_evidence.distinct_s), 5.0, 0, 1e6, "s",
                   "runs ending within this long of the best one are its own, not a runner-up"));
  k.push_back(real("topology.sequence_evidence.min_relative", AT(sequence_evidence.min_relative), -1e6, -1e6, 1e6, "",
                   "the keyframe's own relative similarity z with its match needed as well; -1e6: no such test"));
  k.push_back(real("topology.sequence_evidence.keyframe_interval_s", AT(sequence_evidence.loop.keyframe_interval_s), 1.0,
                   0.01, 1e6, "s", "one keyframe at most this often"));
  k.push_back(real("topology.sequence_evidence.memory_s", AT(sequence_evidence.memory_s), 40.0, 0.02, 1e6, "s",
                   "the longest memory of a run of matches (time constant); must exceed the keyframe interval")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    const SequenceEvidenceConfig& e = c.sequence_evidence;
                    if (e.memory_s > e.loop.keyframe_interval_s) return "";
                    return rangeNumber(e.memory_s) + " is out of range, allowed above keyframe_interval_s = " +
                           rangeNumber(e.loop.keyframe_interval_s) + " s";
                  }));
  k.push_back(integer("topology.sequence_evidence.scales", AT(sequence_evidence.loop.scales), 3, 1, 8, "",
                      "memories integrated side by side, each 4 times shorter than the one before"));
  k.push_back(integer("topology.sequence_evidence.exhaustive_up_to", AT(sequence_evidence.exhaustive_up_to), 1000, 0,
                      1000000000, "keyframes",
                      "compare a keyframe with every earlier one up to this many; beyond, only the candidate index's "
                      "finds, the live runs' next steps and a fixed sample for the statistics (a bounded cost)"));
  k.push_back(integer("topology.sequence_evidence.candidates", AT(sequence_evidence.candidates), 32, 1, 10000, "keyframes",
                      "large maps: keyframes the candidate index proposes per keyframe"));
  k.push_back(integer("topology.sequence_evidence.diagonals", AT(sequence_evidence.diagonals), 32, 1, 10000, "",
                      "large maps: runs of matches followed per memory"));
  k.push_back(integer("topology.sequence_evidence.statistics_sample", AT(sequence_evidence.statistics_sample), 128, 2,
                      100000, "keyframes", "large maps: keyframes compared for the similarities' mean and spread"));
  k.push_back(real("topology.sequence_evidence.min_gap_s", AT(sequence_evidence.min_gap_s), 20.0, 0.01, 1e6, "s",
                   "matches at least this long back")
                  .withCrossCheck([](const DaemonConfig& c) -> std::string {
                    const SequenceEvidenceConfig& e = c.sequence_evidence;
                    const double interval = e.loop.keyframe_interval_s;
                    if (e.min_gap_s >= interval && e.min_gap_s / interval <= 1e6) return "";
                    return rangeNumber(e.min_gap_s) + " is out of range, allowed [keyframe_interval_s = " +
                           rangeNumber(interval) + ", 1e6 x keyframe_interval_s] s";
                  }));
  // Large maps (CandidateSelectionConfig; docs/topology.md): exhaustive up to a size, then an index.
  k.push_back(integer("topology.candidates.exhaustive_up_to", AT(topology.candidates.exhaustive_up_to), 1000, 0,
                      1000000000, "representatives",
                      "compare a new place with every stored representative up to this many; above, through the "
                      "candidate index"));
  k.push_back(integer("topology.candidates.candidates", AT(topology.candidates.candidates), 100, 1, 100000,
                      "representatives", "compared exactly from the index's top"));
  k.push_back(integer("topology.candidates.background_samples", AT(topology.candidates.background_samples), 100, 0,
                      100000, "representatives",
                      "evenly spread stored representatives also compared exactly, for the others' statistics"));
  k.push_back(integer("topology.slice_items", AT(topology_stage.slice_items), 256, 1, 1000000, "work items",
                      "work items per advance() slice (the time budget is checked between slices)"));
  k.push_back(integer("topology.alternatives", AT(topology_stage.alternatives), 3, 0, 16, "nodes",
                      "other nodes published with each place estimate"));
  return k;
}

#undef AT

/// Marks the keys a map records (ConfigKey::recorded_in_map): every key of the stages that decide (the
/// fingerprint, similarity, segmentation and topology sections) except those that only say how the work
/// is spread, what is published or what is kept for localisation (place_views), the keypoint backend (recorded under its older name "keypoints",
/// fingerprintMapSettings, so that maps made before every setting was recorded compare with it), and the
/// seed (a resumed map continues its own random state).
void markMapSettings(std::vector<ConfigKey>& keys) {
  const std::vector<std::string> sections = {"fingerprint.", "similarity.", "segmentation.", "topology."};
  const std::vector<std::string> not_recorded = {"fingerprint.workers", "fingerprint.keypoints.backend",
                                                 "topology.seed", "topology.slice_items", "topology.alternatives",
                                                 "segmentation.place_views"};
  for (ConfigKey& key : keys) {
    bool in_section = false;
    for (const std::string& section : sections) in_section = in_section || key.path.rfind(section, 0) == 0;
    bool excluded = false;
    for (const std::string& path : not_recorded) excluded = excluded || key.path == path;
    key.recorded_in_map = in_section && !excluded;
  }
}

}  // namespace

const std::vector<ConfigKey>& daemonConfigKeys() {
  static const std::vector<ConfigKey> keys = [] {
    std::vector<ConfigKey> k = DaemonKeyTable::makeKeys();
    markMapSettings(k);
    return k;
  }();
  return keys;
}

std::map<std::string, std::string> mapDecisionSettings(const DaemonConfig& config) {
  std::map<std::string, std::string> settings;
  for (const ConfigKey& key : daemonConfigKeys())
    if (key.recorded_in_map) settings[key.path] = key.yamlText(key.get(config));
  return settings;
}

const std::vector<ConfigSection>& daemonConfigSections() {
  static const std::vector<ConfigSection> sections = {
      {"lcm", "LCM transport and channel names"},
      {"lcm.channels", "channel names, 1 .. 255 characters each"},
      {"record", "the frames toposlamd processes, recorded for replay (docs/deploy.md)"},
      {"map", "the map file: where, when it is saved, whether it is resumed, or only localised in"},
      {"map.localize", "localisation only (map.mode: localize): when a frame is not a known node"},
      {"watchdog", "systemd watchdog"},
      {"pipeline", "queues, threads and time budgets of the daemon's pipeline (docs/daemon.md)"},
      {"pipeline.queues", "queue capacities between the stage threads"},
      {"pipeline.threads", "per thread: name, CPU pinning, scheduling policy, priority, nice"},
      {"pipeline.threads.capture", "reads frames from the source"},
      {"pipeline.threads.fingerprint",
       "fingerprints frames (with fingerprint.workers - 1 pool threads tsl-vpack-N, which take its policy, "
       "priority and nice, not its CPU)"},
      {"pipeline.threads.segmentation", "segments the stream into places"},
      {"pipeline.threads.topology", "runs the particle filter over topologies"},
      {"pipeline.threads.publisher", "publishes over LCM"},
      {"pipeline.threads.map_writer", "writes map snapshots (fsync off the frame path)"},
      {"pipeline.threads.lcm_receiver", "toposlamd: receives LCM input (robot motion)"},
      {"pipeline.threads.recorder", "toposlamd with record.dir: encodes and writes the recorded frames"},
      {"fingerprint", "VPACK fingerprint (thesis ch. 3, docs/fingerprint.md)"},
      {"fingerprint.edges", "vertical edges"},
      {"fingerprint.histogram", "HCL colour histograms"},
      {"fingerprint.keypoints", "keypoints per subregion"},
      {"similarity", "n-gram similarity (thesis ch. 3.3, docs/matching.md)"},
      {"similarity.matcher", "which keypoint and histogram matches count"},
      {"segmentation", "Fiedler segmentation (thesis ch. 4, docs/segmentation.md)"},
      {"segmentation.motion",
       "motion-aware segmentation (docs/segmentation.md): with robot motion known (TOPOSLAM_MOTION), frames "
       "taken while the robot stands are left out of the window; without motion, or once the link is lost, "
       "segmentation is by time"},
      {"segmentation.valley", "valley detector on lambda2 (Algorithm 4.1)"},
      {"topology", "particle filter over topologies (thesis ch. 5, docs/topology.md)"},
      {"topology.candidates", "large maps: which stored places a new one is compared with (docs/topology.md)"},
      {"topology.sequence_evidence",
       "the sequence detector: whether each frame is back at an earlier one (place_t's match_*) and, with a weight, "
       "runs of frames as the filter's second evidence (docs/topology.md, \"The per-frame answer\")"},
  };
  return sections;
}

const ConfigKey& daemonConfigKey(std::string_view path) {
  for (const ConfigKey& key : daemonConfigKeys())
    if (key.path == path) return key;
  throw std::out_of_range("no config key '" + std::string(path) + "'");
}

}  // namespace toposlam
