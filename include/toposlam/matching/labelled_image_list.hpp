// Reads the `image,label` CSV files of `toposlam localize` (places and queries). Paths are relative to
// the CSV's folder (absolute paths are kept). Bad lines are reported as "file:line: problem" and
// skipped, so a run goes on with the good ones.
//
// Fields follow RFC 4180 quoting: a field holding a comma or a double quote is written in double quotes
// with inner quotes doubled ("a,b.jpg" or "say ""hi"".jpg"). quoteCsvField (core/csv.hpp, included here
// for the writers of such files) writes such fields, so files written by the project (e.g. localize
// --out) read back unambiguously.
#pragma once

#include <string>
#include <vector>

#include "toposlam/core/csv.hpp"

namespace toposlam {

struct LabelledImage {
  std::string path;  ///< resolved image path
  std::string label;
  std::string source;  ///< "csv_file:line", for messages about this entry (missing image, ...)
};

struct LabelledImageList {
  std::vector<LabelledImage> images;
  std::vector<std::string> problems;  ///< "file:line: what is wrong" for each skipped line
};

/// Accepts an optional header line `image,label`, blank lines and `#` comments; unquoted fields are
/// trimmed; exactly two non-empty fields per line; an unterminated quote or text after a closing quote
/// is a bad line. Throws std::runtime_error when the file cannot be opened.
LabelledImageList readLabelledImageList(const std::string& csv_path);

}  // namespace toposlam
