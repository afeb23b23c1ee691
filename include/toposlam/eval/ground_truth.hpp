// Loop-closure ground truth that comes with a data set rather than from a run: a matrix image
// (samples_GT.bmp: pixel (x=j, y=i) non-zero = frame i shows the same place as frame j) and a CSV of
// loop-closure pairs (samples_GT_pairs.csv: `query_image,matching_images` with space-separated names).
// The simulator's labels.csv is a run-folder file (toposlam/run_folder/run_folder.hpp).
//
// Both loaders throw RunFileError with "<file>[:<line>]: <problem>" for malformed input. Thread-safety:
// pure functions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/run_folder/run_folder.hpp"

namespace toposlam::eval {

/// A loop-closure ground-truth matrix: n x n, row-major, non-zero = same place. Symmetric after loading.
struct LoopClosureMatrix {
  int size = 0;
  std::vector<std::uint8_t> same;  ///< size*size
  bool at(int i, int j) const {
    return same[static_cast<std::size_t>(i) * static_cast<std::size_t>(size) + static_cast<std::size_t>(j)] !=
           0;
  }
};

/// Frame-name pairs from a pairs CSV; resolved to frame numbers against frames.csv by the caller.
struct NamedPair {
  std::string query;
  std::string match;
  int line = 0;  ///< line of the pairs file, for error messages
};

/// Any image OpenCV reads (BMP, PNG); must be square.
LoopClosureMatrix loadLoopClosureImage(const std::string& path);
std::vector<NamedPair> loadLoopClosurePairs(const std::string& path);

}  // namespace toposlam::eval
