// DaemonConfig: YAML -> stage config structs, with strict key and range checking; see the header.
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/config/method_preset.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace toposlam {

namespace {

std::string formatNumber(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// The largest Fiedler value of a window of n frames, n / (n - 1) (thesis eq. 4.6).
double maxLambda2(int window) { return static_cast<double>(window) / static_cast<double>(window - 1); }

std::string describeNode(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

// One YAML mapping being read: remembers which keys were read so finish() can refuse the others.
class Section {
 public:
  Section(YAML::Node node, std::string path) : node_(std::move(node)), path_(std::move(path)) {
    if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap())
      throw ConfigError(where() + ": expected a mapping of keys, got " + describeNode(node_));
  }

  /// An integer in [lo, hi] (inclusive).
  template <typename Int>
  void integer(const char* key, Int& value, long long lo, long long hi, const char* unit = "") {
    std::optional<YAML::Node> found = take(key);
    if (!found) return;
    const YAML::Node& n = *found;
    const std::string range = std::to_string(lo) + " .. " + std::to_string(hi) + unit;
    long long parsed = 0;
    try {
      parsed = n.as<long long>();
    } catch (const YAML::Exception&) {
      throw ConfigError(full(key) + ": expected an integer in " + range + ", got " + describeNode(n));
    }
    if (parsed < lo || parsed > hi)
      throw ConfigError(full(key) + ": " + std::to_string(parsed) + " is out of range, allowed " + range);
    value = static_cast<Int>(parsed);
  }

  /// A real number in [lo, hi]; lo_open/hi_open exclude the bound.
  void real(const char* key, double& value, double lo, double hi, const char* unit = "", bool lo_open = false,
            bool hi_open = false) {
    std::optional<YAML::Node> found = take(key);
    if (!found) return;
    const YAML::Node& n = *found;
    const std::string range = std::string(lo_open ? "(" : "[") + formatNumber(lo) + ", " + formatNumber(hi) +
                              (hi_open ? ")" : "]") + unit;
    double parsed = 0;
    try {
      parsed = n.as<double>();
    } catch (const YAML::Exception&) {
      throw ConfigError(full(key) + ": expected a number in " + range + ", got " + describeNode(n));
    }
    const bool inside = std::isfinite(parsed) && (lo_open ? parsed > lo : parsed >= lo) &&
                        (hi_open ? parsed < hi : parsed <= hi);
    if (!inside) throw ConfigError(full(key) + ": " + formatNumber(parsed) + " is out of range, allowed " + range);
    value = parsed;
  }

  void flag(const char* key, bool& value) {
    std::optional<YAML::Node> found = take(key);
    if (!found) return;
    const YAML::Node& n = *found;
    try {
      value = n.as<bool>();
    } catch (const YAML::Exception&) {
      throw ConfigError(full(key) + ": expected true or false, got " + describeNode(n));
    }
  }

  /// A non-empty string of at most max_length characters.
  void text(const char* key, std::string& value, std::size_t max_length = 4096, bool allow_empty = false) {
    std::optional<YAML::Node> found = take(key);
    if (!found) return;
    const YAML::Node& n = *found;
    if (!n.IsScalar()) throw ConfigError(full(key) + ": expected a string, got " + describeNode(n));
    std::string parsed = n.Scalar();
    if ((!allow_empty && parsed.empty()) || parsed.size() > max_length)
      throw ConfigError(full(key) + ": must have " + (allow_empty ? "0" : "1") + " to " +
                        std::to_string(max_length) + " characters, got '" + parsed + "'");
    value = std::move(parsed);
  }

  /// One of `allowed`.
  std::string choice(const char* key, const std::string& current, std::initializer_list<const char*> allowed) {
    std::optional<YAML::Node> found = take(key);
    if (!found) return current;
    const YAML::Node& n = *found;
    std::string list;
    for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
    if (n.IsScalar())
      for (const char* a : allowed)
        if (n.Scalar() == a) return a;
    throw ConfigError(full(key) + ": " + describeNode(n) + " is not allowed, expected one of: " + list);
  }

  Section child(const char* key) {
    std::optional<YAML::Node> n = take(key, true);
    return Section(n ? *n : YAML::Node(), full(key));
  }

  /// Refuses keys that were never read.
  void finish() const {
    if (!node_.IsMap()) return;
    for (const auto& entry : node_) {
      const std::string key = entry.first.as<std::string>("");
      if (read_.count(key) == 0) {
        std::string known;
        for (const std::string& k : read_) known += (known.empty() ? "" : ", ") + k;
        throw ConfigError("unknown key '" + full(key.c_str()) + "' (known keys" +
                          (path_.empty() ? "" : " under '" + path_ + "'") + ": " + known + ")");
      }
    }
  }

 private:
  // The value of `key`, or nullopt when absent (a default-constructed YAML::Node is a defined null, so
  // absence needs its own state).
  std::optional<YAML::Node> take(const char* key, bool allow_map = false) {
    read_.insert(key);
    if (!node_.IsMap()) return std::nullopt;
    const YAML::Node& map = node_;  // const lookup: the non-const operator[] would insert the key
    YAML::Node n = map[key];
    if (!n.IsDefined()) return std::nullopt;
    if (n.IsNull() && !allow_map) throw ConfigError(full(key) + ": has no value (remove the key to keep the default)");
    if (n.IsMap() && !allow_map) throw ConfigError(full(key) + ": expected a value, got a mapping");
    return n;
  }
  std::string full(const char* key) const { return path_.empty() ? key : path_ + "." + key; }
  std::string where() const { return path_.empty() ? "top level" : path_; }

  YAML::Node node_;
  std::string path_;
  // Every key read (known), in a set so the "known keys" hint is sorted. Keys read but absent count too.
  std::set<std::string> read_;
};

void readThread(Section& threads, const char* key, ThreadSettings& t) {
  Section s = threads.child(key);
  s.text("name", t.name, 15);
  s.integer("cpu", t.cpu, -1, 1023, " (-1 = no pinning)");
  t.policy = s.choice("policy", toString(t.policy), {"other", "fifo"}) == std::string("fifo") ? SchedulingPolicy::Fifo
                                                                                              : SchedulingPolicy::Other;
  s.integer("priority", t.priority, 0, 99, " (1 .. 99 with policy fifo, 0 with other)");
  s.integer("nice", t.nice, -20, 19);
  s.finish();
}

// The method preset's stage settings (method_preset.hpp); keys that follow override them.
void applyPreset(const MethodPreset& preset, DaemonConfig& c) {
  c.preset = preset.name;
  c.fingerprint = preset.fingerprint;
  c.similarity = preset.similarity;
  c.segmentation = preset.segmentation;
  c.topology = preset.topology;
  c.sequence_evidence = preset.sequence_evidence;
}

void readConfig(const YAML::Node& root, DaemonConfig& c) {
  Section top(root, "");
  // The preset first: it gives every stage's defaults, the keys below override them.
  const std::string preset = top.choice("preset", c.preset, {"default", "thesis"});
  if (preset != c.preset) applyPreset(methodPreset(preset), c);
  top.text("source", c.source);
  c.log_level = top.choice("log_level", c.log_level, {"trace", "debug", "info", "warn", "error"});

  {
    Section lcm = top.child("lcm");
    lcm.text("url", c.lcm.url);
    Section channels = lcm.child("channels");
    channels.text("place", c.lcm.place_channel, 255);
    channels.text("place_event", c.lcm.place_event_channel, 255);
    channels.text("topology", c.lcm.topology_channel, 255);
    channels.text("status", c.lcm.status_channel, 255);
    channels.text("motion", c.lcm.motion_channel, 255);
    channels.finish();
    lcm.integer("jpeg_quality", c.lcm.jpeg_quality, 1, 100);
    lcm.real("open_retry_s", c.lcm.open_retry_s, 0, 3600, " seconds (0 = exit 1 at once)");
    lcm.finish();
  }
  {
    Section map = top.child("map");
    map.text("path", c.pipeline.map_path, 4096, true);
    map.flag("load_at_start", c.load_map_at_start);
    map.flag("resume_other_source", c.map_resume_other_source);
    map.real("save_period_s", c.pipeline.map_save_period_s, 0, 86400, " seconds (0 = only at stop)");
    map.real("max_mb", c.map_max_mb, 1, 65536, " MB");
    map.finish();
  }
  {
    Section record = top.child("record");
    record.text("dir", c.record.dir, 4096, true);
    record.real("max_mb", c.record.max_mb, 1, 1e7, " MB");
    c.record.format = record.choice("format", c.record.format, {"jpg", "png"});
    record.integer("jpeg_quality", c.record.jpeg_quality, 1, 100);
    record.integer("queue_frames", c.record.queue_frames, 1, 1024, " frames");
    record.finish();
  }
  {
    Section watchdog = top.child("watchdog");
    watchdog.flag("enabled", c.watchdog);
    watchdog.real("heartbeat_timeout_s", c.pipeline.heartbeat_timeout_s, 0.5, 600, " seconds");
    watchdog.finish();
  }
  {
    Section p = top.child("pipeline");
    Section q = p.child("queues");
    q.integer("frames", c.pipeline.queues.frames, 1, 1024, " frames");
    q.integer("fingerprints", c.pipeline.queues.fingerprints, 1, 1024, " frames");
    q.integer("segmented", c.pipeline.queues.segmented, 1, 1024, " frames");
    q.integer("results", c.pipeline.queues.results, 1, 1024, " frames");
    c.pipeline.queues.overflow = q.choice("overflow", toString(c.pipeline.queues.overflow), {"drop_oldest", "block"}) ==
                                         std::string("block")
                                     ? QueueOverflow::Block
                                     : QueueOverflow::DropOldest;
    q.finish();
    Section threads = p.child("threads");
    readThread(threads, "capture", c.pipeline.threads.capture);
    readThread(threads, "fingerprint", c.pipeline.threads.fingerprint);
    readThread(threads, "segmentation", c.pipeline.threads.segmentation);
    readThread(threads, "topology", c.pipeline.threads.topology);
    readThread(threads, "publisher", c.pipeline.threads.publisher);
    readThread(threads, "map_writer", c.pipeline.threads.map_writer);
    threads.finish();
    p.real("filter_budget_ms", c.pipeline.filter_budget_ms, 0.1, 1000, " milliseconds");
    p.real("status_period_s", c.pipeline.status_period_s, 0.1, 60, " seconds");
    p.integer("thumbnail_width", c.pipeline.thumbnail_width, 16, 1280, " pixels");
    p.finish();
  }
  {
    Section f = top.child("fingerprint");
    f.integer("workers", c.fingerprint_workers, 1, 64, " threads (incl. the fingerprint thread)");
    Section e = f.child("edges");
    e.real("opening_height_fraction", c.fingerprint.edges.opening_height_fraction, 0, 1, "", true);
    e.integer("dilation_width", c.fingerprint.edges.dilation_width, 1, 31, " pixels");
    e.real("mean_factor", c.fingerprint.edges.mean_factor, 0, 100, "", true);
    e.real("min_separation_fraction", c.fingerprint.edges.min_separation_fraction, 0, 0.5, "", true);
    e.finish();
    Section h = f.child("histogram");
    h.real("achromatic_chroma", c.fingerprint.histogram.achromatic_chroma, 0, 1, "", false, true);
    h.real("min_lightness", c.fingerprint.histogram.min_lightness, 0, 1);
    h.real("max_lightness", c.fingerprint.histogram.max_lightness, 0, 1);
    if (c.fingerprint.histogram.max_lightness <= c.fingerprint.histogram.min_lightness)
      throw ConfigError("fingerprint.histogram.max_lightness: " + formatNumber(c.fingerprint.histogram.max_lightness) +
                        " is out of range, allowed (min_lightness = " + formatNumber(c.fingerprint.histogram.min_lightness) + ", 1]");
    h.finish();
    Section k = f.child("keypoints");
    const std::string backend = k.choice("backend", toString(c.fingerprint.keypoints.backend), {"orb", "sift", "brisk", "akaze"});
    c.fingerprint.keypoints.backend = parseKeypointBackend(backend);
    k.integer("max_keypoints", c.fingerprint.keypoints.max_keypoints, 0, 10000);
    k.integer("threshold_iterations", c.fingerprint.keypoints.threshold_iterations, 0, 64);
    k.integer("candidate_limit", c.fingerprint.keypoints.candidate_limit, 0, 100000, " (>= max_keypoints)");
    if (c.fingerprint.keypoints.candidate_limit < c.fingerprint.keypoints.max_keypoints)
      throw ConfigError("fingerprint.keypoints.candidate_limit: " + std::to_string(c.fingerprint.keypoints.candidate_limit) +
                        " is out of range, allowed max_keypoints (" + std::to_string(c.fingerprint.keypoints.max_keypoints) +
                        ") .. 100000");
    k.integer("orb_levels", c.fingerprint.keypoints.orb_levels, 1, 16);
    k.integer("orb_fast_threshold", c.fingerprint.keypoints.orb_fast_threshold, 1, 254);
    k.finish();
    f.integer("min_image_width", c.fingerprint.min_image_width, 4, 100000, " pixels");
    f.integer("min_image_height", c.fingerprint.min_image_height, 4, 100000, " pixels");
    f.finish();
  }
  {
    Section s = top.child("similarity");
    Section m = s.child("matcher");
    m.real("max_hellinger_distance", c.similarity.matcher.max_hellinger_distance, 0, 1, "", true);
    m.real("max_binary_distance_fraction", c.similarity.matcher.max_binary_distance_fraction, 0, 1, "", true);
    m.real("max_float_distance", c.similarity.matcher.max_float_distance, 0, 1e6, " (0 disables the test)");
    m.real("ratio_test", c.similarity.matcher.ratio_test, 0, 1, " (1 disables the test)", true);
    m.flag("mutual_check", c.similarity.matcher.mutual_check);
    m.real("max_angle_difference_deg", c.similarity.matcher.max_angle_difference_deg, 0, 180, " degrees (0 disables the test)");
    m.finish();
    s.real("histogram_weight", c.similarity.histogram_weight, 0, 1);
    s.flag("histogram_gate", c.similarity.histogram_gate);
    s.flag("histogram_only_fallback", c.similarity.histogram_only_fallback);
    c.similarity.keypoint_scoring =
        parseKeypointScoring(s.choice("keypoint_scoring", toString(c.similarity.keypoint_scoring),
                                      {"possible-ngrams", "verified-matches"}));
    s.finish();
  }
  {
    Section s = top.child("segmentation");
    s.real("window_s", c.segmentation.window_s, 0, 3600, " seconds (0 = a window of `window` frames)");
    s.integer("window", c.segmentation.window, 3, 1000, " frames");
    s.integer("min_window_frames", c.segmentation.min_window_frames, 3, 1000, " frames (and <= window)");
    s.real("window_m", c.segmentation.window_m, 0, 1000, " metres (0 = off: no window in distance)");
    s.real("min_frame_spacing_m", c.segmentation.min_frame_spacing_m, 0, 100, " metres (0 = off)");
    s.real("min_frame_spacing_rad", c.segmentation.min_frame_spacing_rad, 0, 10, " rad");
    Section mo = s.child("motion");
    mo.real("standing_speed_mps", c.segmentation_motion.standing_speed_mps, 0, 10, " m/s");
    mo.real("standing_turn_rate_rps", c.segmentation_motion.standing_turn_rate_rps, 0, 100, " rad/s");
    mo.real("standing_after_s", c.segmentation_motion.standing_after_s, 0, 3600, " seconds");
    mo.real("timeout_s", c.segmentation_motion.timeout_s, 0, 3600, " seconds", true);
    mo.finish();
    Section v = s.child("valley");
    v.real("gamma", c.segmentation.valley.gamma, 0, 2, " (and <= window / (window - 1))");
    v.real("delta", c.segmentation.valley.delta, 0, 2, " (and <= gamma)");
    v.finish();
    // Cross-key ranges, checked here so the message names the key in full.
    const double lambda2_max = maxLambda2(c.segmentation.window);
    if (c.segmentation.valley.gamma > lambda2_max)
      throw ConfigError("segmentation.valley.gamma: " + formatNumber(c.segmentation.valley.gamma) +
                        " is out of range, allowed [0, window / (window - 1) = " + formatNumber(lambda2_max) + "]");
    if (c.segmentation.valley.delta > c.segmentation.valley.gamma)
      throw ConfigError("segmentation.valley.delta: " + formatNumber(c.segmentation.valley.delta) +
                        " is out of range, allowed [0, gamma = " + formatNumber(c.segmentation.valley.gamma) + "]");
    s.integer("min_keypoints", c.segmentation.min_keypoints, 0, 10000);
    // Mapped here rather than with parseCutPlacement() so the config reads without the segmentation library.
    const char* placement = c.segmentation.cut_placement == CutPlacement::ValleyFrame ? "valley-frame" : "window-split";
    c.segmentation.cut_placement = s.choice("cut_placement", placement, {"window-split", "valley-frame"}) == "valley-frame"
                                       ? CutPlacement::ValleyFrame
                                       : CutPlacement::WindowSplit;
    s.finish();
  }
  {
    Section t = top.child("topology");
    t.integer("particles", c.topology.particles, 1, 1000000);
    c.topology.likelihood =
        parseLikelihoodModel(t.choice("likelihood", toString(c.topology.likelihood), {"relative", "absolute"}));
    t.real("relative_slope", c.topology.relative_slope, 0, 100, "", true);
    t.real("relative_offset", c.topology.relative_offset, -10, 10);
    t.real("relative_sigma_floor", c.topology.relative_sigma_floor, 0, 1, "", true);
    t.real("alpha", c.topology.alpha, 0, 1e6, "", true);
    t.real("new_node_probability", c.topology.new_node_probability, 0, 1, "", true, true);
    t.real("gamma_shape", c.topology.gamma_shape, 0, 1000, "", true);
    t.real("gamma_scale", c.topology.gamma_scale, 0, 100, "", true);
    t.integer("max_successors", c.topology.max_successors, 1, kTopologyMaxSuccessors);
    t.integer("max_representatives_per_node", c.topology.max_representatives_per_node, 1, kTopologyMaxRepresentatives);
    t.flag("forbid_return_to_previous", c.topology.forbid_return_to_previous);
    t.integer("seed", c.topology.seed, 0, std::numeric_limits<long long>::max());
    t.integer("slice_items", c.topology_slice_items, 1, 1000000, " work items");
    t.integer("alternatives", c.topology_alternatives, 0, 16, " nodes");
    t.finish();
  }
  top.finish();
}

// Documents in a YAML text: a "---" line (marker alone or followed by a space) after content, or content
// after a "..." end line, starts another one. A leading "---" is the first document's optional marker.
int yamlDocumentCount(const std::string& text) {
  int documents = 0;
  bool content = false;  // the current document has a non-comment line
  bool ended = false;    // a "..." line closed it
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const bool start = line.rfind("---", 0) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    const bool end = line.rfind("...", 0) == 0 && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    const std::size_t first = line.find_first_not_of(" \t");
    const bool blank = first == std::string::npos || line[first] == '#';
    if (start) {
      if (content || ended || documents == 0) ++documents;
      content = line.find_first_not_of(" \t", 3) != std::string::npos && line[line.find_first_not_of(" \t", 3)] != '#';
      ended = false;
    } else if (end) {
      ended = true;
    } else if (!blank) {
      if (ended || documents == 0) ++documents;
      ended = false;
      content = true;
    }
  }
  return documents;
}

// yaml-cpp keeps both entries of a repeated key and look-ups see only the first, so the second would be
// ignored silently: refused, naming the key and its line.
void refuseDuplicateKeys(const YAML::Node& node, const std::string& path) {
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) refuseDuplicateKeys(item, path);
    return;
  }
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
    const std::string full = path.empty() ? key : path + "." + key;
    if (!seen.insert(key).second)
      throw ConfigError("duplicate key '" + full + "' (line " + std::to_string(entry.first.Mark().line + 1) +
                        "); give each key once");
    refuseDuplicateKeys(entry.second, full);
  }
}

// Stage validate() messages are "<key>: ..." relative to the stage (fingerprint's are already full).
std::string prefixed(const std::string& section, const std::string& problem) {
  if (problem.empty() || problem.rfind(section + ".", 0) == 0) return problem;
  return section + "." + problem;
}

}  // namespace

DaemonConfig::DaemonConfig() {
  pipeline.map_path = "map.tsm";
  applyPreset(methodPreset(preset), *this);
}

std::string DaemonConfig::validate() const {
  if (source.empty()) return "source: must not be empty (e.g. sim:office?route=loop2 or v4l2:/dev/video0)";
  if (!(map_max_mb >= 1 && map_max_mb <= 65536))
    return "map.max_mb: " + std::to_string(map_max_mb) + " is out of range, allowed [1, 65536] MB";
  if (lcm.url.empty()) return "lcm.url: must not be empty (e.g. udpm://239.255.76.67:7667?ttl=0)";
  {
    // The LCM providers liblcm knows; anything else would only fail when the daemon opens it.
    static const char* const kProviders[] = {"udpm://", "mpudpm://", "memq://", "file://", "tcpq://"};
    bool known = false;
    for (const char* p : kProviders) known = known || lcm.url.rfind(p, 0) == 0;
    if (!known)
      return "lcm.url: '" + lcm.url + "' is not an LCM URL, expected udpm://, mpudpm://, memq://, file:// or tcpq://";
  }
  if (lcm.jpeg_quality < 1 || lcm.jpeg_quality > 100)
    return "lcm.jpeg_quality: " + std::to_string(lcm.jpeg_quality) + " is out of range, allowed 1 .. 100";
  if (!(record.max_mb >= 1 && record.max_mb <= 1e7))
    return "record.max_mb: " + formatNumber(record.max_mb) + " is out of range, allowed [1, 1e+07] MB";
  if (record.format != "jpg" && record.format != "png")
    return "record.format: '" + record.format + "' is not allowed, expected one of: jpg, png";
  if (record.jpeg_quality < 1 || record.jpeg_quality > 100)
    return "record.jpeg_quality: " + std::to_string(record.jpeg_quality) + " is out of range, allowed 1 .. 100";
  if (record.queue_frames < 1 || record.queue_frames > 1024)
    return "record.queue_frames: " + std::to_string(record.queue_frames) + " is out of range, allowed 1 .. 1024 frames";
  if (fingerprint_workers < 1 || fingerprint_workers > 64)
    return "fingerprint.workers: " + std::to_string(fingerprint_workers) + " is out of range, allowed 1 .. 64";
  if (topology_slice_items < 1 || topology_slice_items > 1000000)
    return "topology.slice_items: " + std::to_string(topology_slice_items) + " is out of range, allowed 1 .. 1000000";
  if (topology_alternatives < 0 || topology_alternatives > 16)
    return "topology.alternatives: " + std::to_string(topology_alternatives) + " is out of range, allowed 0 .. 16";
  if (std::string p = pipeline.validate(); !p.empty()) {
    // Map and watchdog keys live in their own YAML sections.
    if (p.rfind("map_save_period_s", 0) == 0) return "map.save_period_s" + p.substr(17);
    if (p.rfind("heartbeat_timeout_s", 0) == 0) return "watchdog." + p;
    return "pipeline." + p;
  }
  if (std::string p = fingerprint.edges.validate(); !p.empty()) return prefixed("fingerprint.edges", p);
  if (std::string p = fingerprint.histogram.validate(); !p.empty()) return prefixed("fingerprint.histogram", p);
  if (std::string p = fingerprint.keypoints.validate(); !p.empty()) return prefixed("fingerprint.keypoints", p);
  if (std::string p = fingerprint.validate(); !p.empty()) return prefixed("fingerprint", p);
  if (std::string p = similarity.validate(); !p.empty()) return prefixed("similarity", p);
#ifdef TOPOSLAM_HAVE_SEGMENTATION
  if (std::string p = segmentation.validate(); !p.empty()) return prefixed("segmentation", p);
  if (std::string p = segmentation_motion.validate(); !p.empty()) return prefixed("segmentation.motion", p);
#endif
#ifdef TOPOSLAM_HAVE_TOPOLOGY
  if (std::string p = topology.validate(); !p.empty()) return prefixed("topology", p);
#endif
  return "";
}

DaemonConfig parseDaemonConfig(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    // A second document ("---") would be ignored silently by YAML::Load: refused instead. Found by
    // scanning the lines, not with YAML::LoadAll, which loops forever on some malformed input in
    // yaml-cpp 0.7 (found by fuzz_config; tests/fuzz/corpus/config/loadall-hang).
    if (const int documents = yamlDocumentCount(yaml_text); documents > 1)
      throw ConfigError(origin + ": holds " + std::to_string(documents) +
                        " YAML documents (a '---' line starts another); toposlamd reads exactly one");
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ": not valid YAML: " + e.what());
  }
  try {
    refuseDuplicateKeys(root, "");
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  DaemonConfig config;
  try {
    readConfig(root, config);
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  if (std::string problem = config.validate(); !problem.empty()) throw ConfigError(origin + ": " + problem);
  return config;
}

DaemonConfig loadDaemonConfig(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw ConfigError("the config file '" + path + "' is a folder; give the YAML file in it (e.g. " +
                      (std::filesystem::path(path) / "toposlam.yaml").string() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError("cannot read the config file '" + path + "' (does it exist and is it readable?)");
  // Read at most the cap (+1 to notice more): /dev/zero or a runaway file never reads forever.
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw ConfigError("cannot read the config file '" + path + "'");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes)
    throw ConfigError("the config file '" + path + "' is larger than " + std::to_string(kMaxConfigBytes >> 10) +
                      " KiB; is it really a toposlam config?");
  return parseDaemonConfig(text, path);
}

}  // namespace toposlam
