// `toposlam-bench pipeline`: the whole real-time pipeline as toposlamd runs it (capture, fingerprint,
// segmentation, topology filter, LCM publish; the same stage adapters, threads and queues), at each frame
// size, on one CPU and on two. Frames are rendered by the source (default: the simulated office) BEFORE
// the runs and kept in memory, then played in a loop, so the renderer's cost does not count against the
// pipeline; the places repeat with the loop, so filter steps (and revisits) happen throughout.
//
// Two runs per size and CPU count:
//   throughput   the source as fast as the pipeline takes frames (lossless `block` queues): sustained fps;
//   paced        the source at --rate Hz (a camera), drop-oldest queues: capture-to-publish latency.
// Both report latency (all frames, and apart the frames on which a place closed or its filter step
// finished), per-stage ms (fingerprint, segmentation, topology filter, publish), drops, places and the
// run's peak resident memory. A table, or JSON with --json. Prints numbers, fails nothing.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "benchmarks.hpp"
#include "lcm_channels.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/core/worker_pool.hpp"
#include "toposlam/io/source_factory.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/pipeline.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam/platform/process_resources.hpp"
#include "toposlam/platform/thread_os.hpp"

namespace toposlam::cli {

namespace {

struct PipelineBenchOptions {
  std::string source = "sim:office?route=loop2&seed=1";
  std::vector<std::string> sizes = {"320x240", "640x480"};
  std::vector<int> cores = {1, 2};
  int frames = 600;           ///< published frames per run
  int distinct_frames = 100;  ///< rendered once, played in a loop
  double source_fps = 5.0;    ///< the frames' own clock (segmentation windows are in seconds of it)
  double rate = 30.0;         ///< paced runs: frames per second
  std::string config;         ///< a toposlamd config file ("" = built-in defaults)
  std::string lcm_url = "memq://";
  bool json = false;
};

/// Adds or replaces one query parameter of a source URI.
std::string withParameter(const std::string& uri, const std::string& key, const std::string& value) {
  const std::size_t q = uri.find('?');
  const std::string base = q == std::string::npos ? uri : uri.substr(0, q);
  std::istringstream parts(q == std::string::npos ? "" : uri.substr(q + 1));
  std::string part, query;
  while (std::getline(parts, part, '&'))
    if (!part.empty() && part.rfind(key + "=", 0) != 0) query += (query.empty() ? "" : "&") + part;
  query += (query.empty() ? "" : "&") + key + "=" + value;
  return base + "?" + query;
}

/// Frames held in memory, played `total` times in a loop; paced at `rate` Hz when rate > 0.
class LoopedFrameSource final : public FrameSource {
 public:
  LoopedFrameSource(const std::vector<cv::Mat>& images, double source_fps, int total, double rate)
      : images_(images), source_fps_(source_fps), total_(total), rate_(rate) {}
  std::string describe() const override { return "memory (" + std::to_string(images_.size()) + " frames, looped)"; }
  std::optional<Frame> next() override {
    if (interrupted_.load() || next_ >= total_) return std::nullopt;
    if (rate_ > 0) {
      if (next_ == 0) start_ = std::chrono::steady_clock::now();
      std::this_thread::sleep_until(start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                 std::chrono::duration<double>(next_ / rate_)));
    }
    Frame f;
    f.image = images_[static_cast<std::size_t>(next_) % images_.size()];  // shared, not copied
    f.sequence = next_;
    f.timestamp_s = next_ / source_fps_;
    ++next_;
    return f;
  }
  void interrupt() override { interrupted_.store(true); }
  std::int64_t frameCountHint() const override { return total_; }

 private:
  const std::vector<cv::Mat>& images_;
  double source_fps_;
  int total_;
  double rate_;
  int next_ = 0;
  std::atomic<bool> interrupted_{false};
  std::chrono::steady_clock::time_point start_;
};

/// Forwards to the LCM sink, timing it, and keeps each published frame's stage times.
class RecordingSink final : public PipelineSink {
 public:
  explicit RecordingSink(PipelineSink& inner) : inner_(inner) {}
  void publish(const FrameResult& r) override {
    const auto t0 = std::chrono::steady_clock::now();
    inner_.publish(r);
    const double took_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!r.has_frame) return;
    fingerprint_ms.push_back(r.fingerprint_ms);
    segmentation_ms.push_back(r.segmentation_ms);
    filter_ms.push_back(r.filter_ms);
    publish_ms.push_back(took_ms);
    place_frame.push_back(r.closed_place.has_value() || !r.finished_places.empty());
    places += static_cast<int>(r.finished_places.size());
  }
  void publishStatus(const PipelineStatus& s) override { inner_.publishStatus(s); }

  std::vector<double> fingerprint_ms, segmentation_ms, filter_ms, publish_ms;
  std::vector<bool> place_frame;  ///< same order as Pipeline::latencies()
  int places = 0;

 private:
  PipelineSink& inner_;
};

struct RunResult {
  std::string size, mode;
  int cores = 0;
  double fps = 0;
  std::int64_t frames = 0, dropped = 0;
  int places = 0;
  LatencyStats latency, place_latency, fingerprint, segmentation, topology, publish;
  double peak_rss_mb = 0, frames_mb = 0;
  std::string error;
};

cv::Size parseSize(const std::string& text) {
  int w = 0, h = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || x != 'x' || w < 16 || h < 16 || w > 4096 || h > 4096)
    throw CLI::ValidationError("--sizes", "'" + text + "' is not WIDTHxHEIGHT (16 .. 4096 each)");
  return {w, h};
}

std::vector<cv::Mat> renderFrames(const std::string& source, const std::string& size, int count) {
  std::unique_ptr<FrameSource> s = openFrameSource(withParameter(source, "size", size));
  std::vector<cv::Mat> frames;
  while (static_cast<int>(frames.size()) < count) {
    std::optional<Frame> f = s->next();
    if (!f) break;
    frames.push_back(f->image.clone());  // the source may reuse its buffer
  }
  if (frames.empty()) throw std::runtime_error("bench pipeline: the source " + source + " gave no frame");
  return frames;
}

RunResult runOnce(const DaemonConfig& base, const PipelineBenchOptions& o, const std::vector<cv::Mat>& images,
                  const std::string& size, int cores, bool paced) {
  RunResult out;
  out.size = size;
  out.cores = cores;
  out.mode = paced ? "paced" : "throughput";
  DaemonConfig c = base;
  c.map.path.clear();
  c.pipeline.record_latencies = true;
  c.pipeline.queues.overflow = paced ? QueueOverflow::DropOldest : QueueOverflow::Block;
  SteadyClock clock;
  const LcmChannels channels = channelsOf(c.lcm);
  // Every thread of the run (worker pool, stage threads, OpenCV's) is created below and inherits this.
  const std::vector<int> all = allowedCpus();
  if (const std::string problem = restrictToCpus(std::vector<int>(all.begin(), all.begin() + cores)); !problem.empty())
    out.error = problem;
  std::size_t frame_bytes = 0;
  for (const cv::Mat& m : images) frame_bytes += m.total() * m.elemSize();
  out.frames_mb = static_cast<double>(frame_bytes) / (1024.0 * 1024.0);
  resetPeakResident();
  {
    LcmPipelineSink lcm(o.lcm_url, channels, c.lcm.jpeg_quality);
    RecordingSink sink(lcm);
    LoopedFrameSource source(images, o.source_fps, o.frames, paced ? o.rate : 0.0);
    WorkerPool pool(c.fingerprint_stage.workers, namedWorkers("tsl-vpack"));
    VpackFingerprintStage fingerprint(c.fingerprint, &pool, c.fingerprint_stage.thumbnail_width);
    NgramSimilarity similarity(c.similarity);
    FiedlerSegmentationStage segmentation(c.segmentation, similarity, 600, c.segmentation_stage.motion);
    ParticleFilterTopologyStage topology(c.topology, similarity, clock, c.topology_stage);
    Pipeline pipeline(c.pipeline, c.map, c.watchdog, source, fingerprint, segmentation, topology, sink,
                      clock);
    const double t0 = clock.now();
    pipeline.start();
    pipeline.wait();  // the source ends after o.frames frames
    const double elapsed = clock.now() - t0;
    std::vector<double> latencies = pipeline.latencies();
    std::vector<double> place_latencies;
    for (std::size_t i = 0; i < latencies.size() && i < sink.place_frame.size(); ++i)
      if (sink.place_frame[i]) place_latencies.push_back(latencies[i]);
    out.frames = static_cast<std::int64_t>(latencies.size());
    out.fps = elapsed > 0 ? static_cast<double>(latencies.size()) / elapsed : 0.0;
    out.latency = summarizeLatencies(latencies);
    out.place_latency = summarizeLatencies(place_latencies);
    out.fingerprint = summarizeLatencies(sink.fingerprint_ms);
    out.segmentation = summarizeLatencies(sink.segmentation_ms);
    out.topology = summarizeLatencies(sink.filter_ms);
    out.publish = summarizeLatencies(sink.publish_ms);
    out.dropped = pipeline.status().frames_dropped;
    out.places = sink.places;
    if (!pipeline.error().empty()) out.error = pipeline.error();
  }
  out.peak_rss_mb = static_cast<double>(peakResidentBytes()) / (1024.0 * 1024.0);
  restrictToCpus(all);
  return out;
}

void writeStats(JsonWriter& json, const char* name, const LatencyStats& s) {
  json.key(name).beginObject();
  json.field("median_ms", s.median_ms).field("p99_ms", s.p99_ms).field("max_ms", s.max_ms);
  json.field("samples", s.samples);
  json.endObject();
}

std::string triple(const LatencyStats& s) {
  char text[64];
  std::snprintf(text, sizeof text, "%.2f/%.2f/%.2f", s.median_ms, s.p99_ms, s.max_ms);
  return text;
}

void runPipelineBench(const PipelineBenchOptions& o) {
  const DaemonConfig base = o.config.empty() ? DaemonConfig() : loadDaemonConfig(o.config);
  if (const std::string problem = base.validate(); !problem.empty()) throw std::invalid_argument(problem);
  const std::vector<int> all = allowedCpus();
  std::vector<RunResult> results;
  std::vector<std::string> notes;
  for (const std::string& size : o.sizes) {
    parseSize(size);
    const std::vector<cv::Mat> images = renderFrames(o.source, size, o.distinct_frames);
    for (const int cores : o.cores) {
      if (cores > static_cast<int>(all.size())) {
        notes.push_back(size + ": " + std::to_string(cores) + " CPUs asked, " + std::to_string(all.size()) +
                        " allowed: skipped");
        continue;
      }
      for (const bool paced : {false, true}) results.push_back(runOnce(base, o, images, size, cores, paced));
    }
  }
  if (o.json) {
    JsonWriter json(std::cout);
    json.beginObject();
    json.field("source", o.source).field("distinct_frames", o.distinct_frames).field("frames_per_run", o.frames);
    json.field("paced_rate_hz", o.rate).field("filter_budget_ms", base.pipeline.filter_budget_ms);
    json.field("particles", base.topology.particles).field("opencv_threads", base.pipeline.opencv_threads);
    json.field("lcm_url", o.lcm_url);
    json.key("runs").beginArray();
    for (const RunResult& r : results) {
      json.beginObject();
      json.field("size", r.size).field("cores", r.cores).field("mode", r.mode).field("fps", r.fps);
      json.field("frames", r.frames).field("dropped", r.dropped).field("places", r.places);
      writeStats(json, "latency", r.latency);
      writeStats(json, "place_frame_latency", r.place_latency);
      json.key("stages").beginObject();
      writeStats(json, "fingerprint", r.fingerprint);
      writeStats(json, "segmentation", r.segmentation);
      writeStats(json, "topology", r.topology);
      writeStats(json, "publish", r.publish);
      json.endObject();
      json.field("peak_rss_mb", r.peak_rss_mb).field("frames_mb", r.frames_mb);
      if (!r.error.empty()) json.field("error", r.error);
      json.endObject();
    }
    json.endArray();
    json.key("notes").beginArray();
    for (const std::string& n : notes) json.value(n);
    json.endArray();
    json.endObject();
    std::cout << "\n";
    return;
  }
  std::printf("pipeline: %s, %d frames rendered once and looped, %d frames per run; paced at %.0f Hz; filter "
              "budget %.1f ms, %d particles, OpenCV threads %d, LCM %s\n",
              o.source.c_str(), o.distinct_frames, o.frames, o.rate, base.pipeline.filter_budget_ms,
              base.topology.particles, base.pipeline.opencv_threads, o.lcm_url.c_str());
  std::printf("latency = capture to publish, ms median/p99/max; place = frames on which a place closed or its "
              "filter step finished; peak MB includes the frames held in memory (frames MB)\n");
  std::printf("%-8s %5s %-10s %7s %20s %20s %6s %6s %7s %7s\n", "size", "cores", "mode", "fps", "latency",
              "place latency", "drops", "places", "peakMB", "framesMB");
  for (const RunResult& r : results) {
    std::printf("%-8s %5d %-10s %7.1f %20s %20s %6lld %6d %7.1f %7.1f\n", r.size.c_str(), r.cores, r.mode.c_str(),
                r.fps, triple(r.latency).c_str(), triple(r.place_latency).c_str(), static_cast<long long>(r.dropped),
                r.places, r.peak_rss_mb, r.frames_mb);
  }
  std::printf("\nper-stage ms, median/p99/max (topology = filter work spent on the frame)\n");
  std::printf("%-8s %5s %-10s %20s %20s %20s %20s\n", "size", "cores", "mode", "fingerprint", "segmentation",
              "topology", "publish");
  for (const RunResult& r : results) {
    std::printf("%-8s %5d %-10s %20s %20s %20s %20s\n", r.size.c_str(), r.cores, r.mode.c_str(),
                triple(r.fingerprint).c_str(), triple(r.segmentation).c_str(), triple(r.topology).c_str(),
                triple(r.publish).c_str());
    if (!r.error.empty()) std::printf("  error: %s\n", r.error.c_str());
  }
  for (const std::string& n : notes) std::printf("note: %s\n", n.c_str());
}

}  // namespace

void addBenchPipeline(CLI::App& bench) {
  auto o = std::make_shared<PipelineBenchOptions>();
  auto* cmd = bench.add_subcommand(
      "pipeline", "the whole pipeline as toposlamd runs it: fps, capture-to-publish latency, stage ms, peak RSS");
  cmd->add_option("--source", o->source, "Source URI rendered once (size= is set per run)")->capture_default_str();
  cmd->add_option("--sizes", o->sizes, "Frame sizes, WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--cores", o->cores, "CPU counts to run on (the first N the process may use)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Published frames per run")->check(CLI::Range(10, 1000000))->capture_default_str();
  cmd->add_option("--distinct-frames", o->distinct_frames, "Frames rendered and looped")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--source-fps", o->source_fps, "The frames' own clock, Hz (segmentation windows are seconds)")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  cmd->add_option("--rate", o->rate, "Paced runs: frames per second")->check(CLI::Range(1.0, 10000.0))->capture_default_str();
  cmd->add_option("-c,--config", o->config, "toposlamd config file (default: built-in defaults)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--lcm-url", o->lcm_url, "Where to publish (memq:// stays in the process)")->capture_default_str();
  cmd->add_flag("--json", o->json, "JSON instead of the table");
  cmd->callback([o] { runPipelineBench(*o); });
}

}  // namespace toposlam::cli
