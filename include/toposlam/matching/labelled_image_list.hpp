// Reads the `image,label` CSV files of `toposlam localize` (places and queries). Paths are relative to
// the CSV's folder (absolute paths are kept). Bad lines are reported as "file:line: problem" and
// skipped, so a run goes on with the good ones.
#pragma once

#include <string>
#include <vector>

namespace toposlam {

struct LabelledImage {
  std::string path;   ///< resolved image path
  std::string label;
  std::string source; ///< "csv_file:line", for messages about this entry (missing image, ...)
};

struct LabelledImageList {
  std::vector<LabelledImage> images;
  std::vector<std::string> problems;  ///< "file:line: what is wrong" for each skipped line
};

/// Accepts an optional header line `image,label`, blank lines and `#` comments; fields are trimmed;
/// exactly two non-empty fields per line. Throws std::runtime_error when the file cannot be opened.
LabelledImageList readLabelledImageList(const std::string& csv_path);

}  // namespace toposlam
