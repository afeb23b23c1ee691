// Shared pieces of the offline commands that write a run folder (`segment`, `map`): opening the frame
// source, creating output files with an actionable error, timing.csv, and the one block of
// segmentation options both commands take (defaults from FiedlerSegmenterConfig).
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "toposlam/core/output_file.hpp"
#include "toposlam/io/frame_source.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

namespace toposlam::cli {

/// Opens a source URI (images:, video:, sim:, ...); throws FrameSourceError when it cannot.
std::unique_ptr<FrameSource> openSource(const std::string& uri);

/// An output file of the run folder (core/output_file.hpp): written under a temporary name; call
/// commit() when done, which checks every write and renames it over `path`. Throws OutputFileError
/// naming the file (cannot create it, a full disk, ...). Not committed: nothing is written.
OutputFile openOutput(const std::filesystem::path& path);

/// Creates the run folder; throws std::runtime_error naming it when it cannot.
void createRunFolder(const std::string& dir);

/// One row of timing.csv, milliseconds.
struct FrameTiming {
  double fingerprint_ms = 0.0;
  double segment_ms = 0.0;
  std::optional<double> filter_ms;  ///< empty column when the command has no filter (`segment`)
};
void writeTimingCsv(const std::filesystem::path& path, const std::vector<FrameTiming>& rows);

/// --window, --gamma, --delta, --similarity-floor, --min-keypoints, --cut.
struct SegmentationOptions {
  FiedlerSegmenterConfig config;
  std::string cut = toString(FiedlerSegmenterConfig{}.cut_placement);
};
void addSegmentationOptions(CLI::App& command, SegmentationOptions& options);
/// The validated segmenter config; throws std::invalid_argument "<command>: <key>: <problem>".
FiedlerSegmenterConfig segmenterConfig(const SegmentationOptions& options, const std::string& command);

}  // namespace toposlam::cli
