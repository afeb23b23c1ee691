// `toposlam eval RUN_DIR --truth labels.csv|GT.bmp|pairs.csv [--tolerance k] [--json]`: measures a run
// folder (from `segment` or `map`) against ground truth and prints the tables (docs/evaluation.md):
// localisation (thesis Table 3.1), loop-closure precision-recall, segmentation boundaries, places per
// traversal and consistency, topology (one-to-one, merged, split, wrong loop closures). Writes
// RUN_DIR/eval.json. Several labels files (one per traversal, in the order the run read them) may be given.
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "eval_cli_options.hpp"
#include "toposlam/platform/output_file.hpp"
#include "toposlam/eval/evaluation.hpp"

namespace toposlam::cli {

namespace {

struct EvalCommandOptions {
  std::string run_dir;
  std::vector<std::string> truth;
  eval::EvalOptions eval;
  bool json = false;
};

void runEval(const EvalCommandOptions& o) {
  const RunData run = loadRun(o.run_dir);
  const eval::Truth truth = eval::loadTruth(o.truth);
  const eval::EvalResult result = eval::evaluate(run, truth, o.eval);
  const std::filesystem::path json_path = std::filesystem::path(o.run_dir) / "eval.json";
  // Temporary name, checked, renamed: a full disk is an error naming the file and the eval.json of an
  // earlier run is kept whole (it used to be truncated to what fitted).
  OutputFile json(json_path);
  eval::writeEvalJson(json, result);
  json.commit();
  if (o.json) {
    eval::writeEvalJson(std::cout, result);
  } else {
    std::cout << eval::formatEvalText(result) << "\nwrote " << json_path.string() << "\n";
  }
}

}  // namespace

void addEvalMeasureOptions(CLI::App& cmd, eval::EvalOptions& options) {
  cmd.add_option("--tolerance", options.tolerance, "Frames a place cut may be off a room change")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd.add_option("--min-gap", options.min_gap,
                 "Loop closures: ignore frame pairs at most this many frames apart (-1 = 25 for a matrix or "
                 "pairs file, 0 for labels)")
      ->check(CLI::Range(-1, 100000))
      ->capture_default_str();
  cmd.add_option(
         "--traversals", options.traversals,
         "Split the frames evenly into N traversals when the labels do not say (no traversal column); "
         "0 = one per labels file, or per source of `map`")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd.add_option("--thresholds", options.thresholds, "Probability thresholds of the localisation table")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
}

void addEvalCommand(CLI::App& app) {
  auto options = std::make_shared<EvalCommandOptions>();
  auto* cmd =
      app.add_subcommand("eval", "Measure a run folder against ground truth (tables + RUN_DIR/eval.json)");
  cmd->add_option("run_dir", options->run_dir, "Run folder written by `toposlam segment` or `toposlam map`")
      ->required();
  cmd->add_option(
         "--truth", options->truth,
         "labels.csv (frame,room; several = one per traversal, in order), a loop-closure matrix image "
         "(like samples_GT.bmp) or a pairs CSV (like samples_GT_pairs.csv)")
      ->required();
  addEvalMeasureOptions(*cmd, options->eval);
  cmd->add_flag("--json", options->json, "Print eval.json instead of the tables");
  cmd->callback([options] { runEval(*options); });
}

}  // namespace toposlam::cli
