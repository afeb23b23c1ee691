// `toposlam segment SOURCE --out DIR`: online place segmentation of a frame stream (thesis chapter 4).
// Every frame is fingerprinted (VPACK), compared with the window's other frames (n-gram similarity) and
// fed to the FiedlerSegmenter. Writes the run folder of docs/run-folder.md: frames.csv, places.csv,
// dropped_places.csv, timing.csv and lambda2.svg (thesis Figure 4.10). Progress goes to stderr.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "motion_input.hpp"
#include "offline_run_io.hpp"
#include "timing.hpp"
#include "toposlam/core/worker_pool.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/io/source_uri.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "toposlam/platform/thread_os.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/offline_runner.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/frame_failures.hpp"
#include "toposlam/pipeline/stage_assembly.hpp"
#include "toposlam/run_folder/run_folder.hpp"
#include "progress.hpp"
#include "toposlam/core/json_writer.hpp"

namespace toposlam::cli {

namespace {

struct SegmentOptions {
  std::string source;
  std::string out;
  ConfigOptions config;  ///< -c, --set, --preset and the segmentation's aliases (config_options.hpp)
  MotionOptions motion;
  std::int64_t max_frames = 0;
  int workers = 1;
  bool quiet = false;
  bool json = false;
};

void runSegment(const SegmentOptions& o) {
  DaemonConfig settings = commandConfig(o.config);
  std::optional<MotionReplay> motion = openMotion(o.motion, 1, "segment", settings.segmentation);
  const FiedlerSegmenterConfig& config = settings.segmentation;
  createRunFolder(o.out);

  std::unique_ptr<FrameSource> source = openSource(o.source);
  std::unique_ptr<WorkerPool> pool;
  if (o.workers > 1) pool = std::make_unique<WorkerPool>(o.workers, namedWorkers("segment"));
  // toposlamd's stages (stage_assembly.hpp), the topology one unused; no thumbnails: no place events here.
  const ManualClock clock;
  StageAssembly stages(settings, clock, pool.get(), Thumbnails::None);
  FiedlerSegmentationStage& segmentation_stage = stages.segmentation();
  OfflineRunner pipeline(stages.fingerprint(), segmentation_stage);

  const std::int64_t total = source->frameCountHint();
  if (!o.quiet) std::cerr << "segment: " << source->describe() << "\n";
  std::vector<double> fingerprint_ms, segment_ms;
  std::vector<TimingRow> timing;
  FrameFailures failures;  // the one per-frame error policy (frame_failures.hpp)
  // The window's clock: the frames' timestamps with any step back cut out (the segmentation stage's;
  // docs/reliability.md, "Clock jumps"); frames.csv records it. Motion is looked up at the frame's own
  // timestamp (the motion file's clock is the recording's).
  Progress progress("segment", "frames", o.max_frames > 0 && (total <= 0 || total > o.max_frames) ? o.max_frames : total,
                    o.quiet);
  std::int64_t read = 0;
  while (o.max_frames <= 0 || static_cast<std::int64_t>(pipeline.run().frames.size()) < o.max_frames) {
    std::optional<Frame> frame = source->next();
    if (!frame) break;
    progress.update(++read);
    Stopwatch fingerprint_watch;
    std::shared_ptr<const Fingerprint> fingerprint;
    try {
      fingerprint = pipeline.fingerprint(frame->image, frame->grey);
    } catch (const std::exception& e) {
      // A frame the stages refuse (empty, too small): skipped and counted, as toposlamd does.
      progress.clearLine();
      if (failures.count())
        std::cerr << "segment: skipping frame '" << frame->name << "' (" << failures.total() << " so far): "
                  << e.what() << "\n";
      continue;
    }
    fingerprint_ms.push_back(fingerprint_watch.elapsedMs());
    Stopwatch segment_watch;
    if (motion) motion->feedUpTo(frame->timestamp_s, segmentation_stage);
    pipeline.segment(frame->timestamp_s, frame->name, std::move(fingerprint));
    segment_ms.push_back(segment_watch.elapsedMs());
    timing.push_back(TimingRow{static_cast<std::int64_t>(timing.size()), fingerprint_ms.back(), segment_ms.back(), std::nullopt});
  }
  pipeline.finish();
  progress.finish();
  const std::int64_t refused = failures.total();
  if (const FrameTimeline& timeline = segmentation_stage.sourceTimeline(); timeline.stepsBack() > 0)
    std::cerr << timelineSummary(timeline, "segment") << "\n";
  if (motion) std::cerr << motionSummary(segmentation_stage, o.motion, "segment") << "\n";

  const SegmentationRun& run = pipeline.run();
  if (run.frames.empty()) {
    throw std::runtime_error(o.source + ": the source gave no usable frames (" +
                             std::to_string(source->skippedFrames() + refused) + " skipped)");
  }
  const std::filesystem::path dir(o.out);
  writeSources(dir, {absoluteSourceUri(o.source)});
  writeFrames(dir, frameRows(run), FrameColumns::Segmentation);
  writePlaces(dir, placeRows(run.places));
  writeDroppedPlaces(dir, placeRows(run.dropped_places));
  writeTiming(dir, timing);
  writeLambda2Plot(dir, run, config, "Fiedler value over " + o.source);

  const TimingSummary f = summarize(fingerprint_ms);
  const TimingSummary s = summarize(segment_ms);
  if (o.json) {
    JsonWriter json(std::cout);
    json.beginObject()
        .field("frames", run.frames.size())
        .field("places", run.places.size())
        .field("dropped_places", run.dropped_places.size())
        .field("skipped_frames", source->skippedFrames() + refused)
        .field("window", config.window)
        .field("gamma", config.valley.gamma)
        .field("delta", config.valley.delta)
        .field("fingerprint_ms_median", f.median_ms)
        .field("fingerprint_ms_p99", f.p99_ms)
        .field("segment_ms_median", s.median_ms)
        .field("segment_ms_p99", s.p99_ms)
        .field("out", o.out)
        .endObject();
    std::cout << "\n" << std::flush;
    return;
  }
  std::printf(
      "%zu frames -> %zu places kept, %zu dropped (fewer than %d keypoints); window %d, gamma %.3g, "
      "delta %.3g, similarity floor %.3g, %s\n",
      run.frames.size(), run.places.size(), run.dropped_places.size(), config.min_keypoints, config.window,
      config.valley.gamma, config.valley.delta, config.similarity_floor, toString(config.cut_placement));
  std::printf("ms per frame: fingerprint median %.2f p99 %.2f; segment median %.3f p99 %.3f\n", f.median_ms,
              f.p99_ms, s.median_ms, s.p99_ms);
  if (source->skippedFrames() + refused > 0) {
    // The source's by reason, as toposlamd's last log line, then the frames the extractor refused.
    std::string line = "skipped frames: " + std::to_string(source->skippedFrames() + refused);
    if (const std::string by_reason = skippedFramesText(source->skippedByReason()); !by_reason.empty())
      line += " " + by_reason.substr(by_reason.find('('));  // "(truncated 2, corrupt 1)"
    if (refused > 0) line += "; refused by the extractor " + std::to_string(refused);
    std::printf("%s\n", line.c_str());
  }
  std::printf("wrote %s/{frames,places,dropped_places,timing}.csv and lambda2.svg\n", o.out.c_str());
}

}  // namespace

void addSegmentCommand(CLI::App& app) {
  auto options = std::make_shared<SegmentOptions>();
  auto* cmd = app.add_subcommand("segment",
                                 "Segment a frame stream into places by algebraic connectivity "
                                 "(thesis chapter 4)");
  cmd->add_option("source", options->source,
                  "Frame source URI: images:FOLDER_OR_GLOB, video:FILE, sim:WORLD?route=..., ...")
      ->required();
  cmd->add_option("--out", options->out, "Output run folder (created if missing)")->required();
  addConfigOptions(*cmd, options->config);
  addSegmentationOptions(*cmd, options->config);
  addMotionOptions(*cmd, options->motion);
  cmd->add_option("--max-frames", options->max_frames, "Stop after this many frames (0: whole stream)");
  cmd->add_option("--workers", options->workers, "Threads for the fingerprint's subregions")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
  cmd->add_flag("--json", options->json, "Print the summary as one JSON object (frames, places, timings)");
  cmd->callback([options] { runSegment(*options); });
}

}  // namespace toposlam::cli
