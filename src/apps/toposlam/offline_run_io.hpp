// Shared pieces of the offline commands (`segment`, `map`, and the other commands' output files): opening
// the frame source, creating output files with an actionable error, and the one block of segmentation
// options `segment` and `map` take (aliases of the key table's keys). The run folder's files are
// run_folder's (toposlam/run_folder/run_folder.hpp).
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core/mat.hpp>

#include "config_options.hpp"
#include "toposlam/core/frame_timeline.hpp"
#include "toposlam/platform/output_file.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

namespace toposlam::cli {

/// Opens a source URI (images:, video:, sim:, ...); throws FrameSourceError when it cannot.
std::unique_ptr<FrameSource> openSource(const std::string& uri);

/// An output file of the run folder (core/output_file.hpp): written under a temporary name; call
/// commit() when done, which checks every write and renames it over `path`. Throws OutputFileError
/// naming the file (cannot create it, a full disk, ...). Not committed: nothing is written.
OutputFile openOutput(const std::filesystem::path& path);

/// Writes `image` to `path` in the format its extension names (.png, .jpg, ...) through an OutputFile:
/// encoded in memory, written under a temporary name, checked and renamed. Throws OutputFileError naming
/// the file when it cannot be encoded or written (a full disk), so an image is never reported as written
/// when it is not, and a failed write leaves the old file in place.
void writeImageFile(const std::filesystem::path& path, const cv::Mat& image);

/// "COMMAND: the source's clock went back N times (the last by X s): ..." for a source whose timestamps
/// stepped back (docs/reliability.md, "Clock jumps").
std::string timelineSummary(const FrameTimeline& timeline, const std::string& command);

/// The segmentation's aliases (--window-s, --window, --min-window-frames, --gamma, --delta, --similarity-floor,
/// --min-keypoints, --cut, --doorway-shift-s, --doorway-borders, --representative, --representative-interval-s,
/// --place-samples) and --keypoints, shared by `segment` and `map`: each sets its key (config_options.hpp).
void addSegmentationOptions(CLI::App& command, ConfigOptions& options);

}  // namespace toposlam::cli
