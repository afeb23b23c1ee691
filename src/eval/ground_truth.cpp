// Loop-closure ground truth (see ground_truth.hpp).
#include "toposlam/eval/ground_truth.hpp"

#include <sstream>

#include "toposlam/io/image_file.hpp"

namespace toposlam::eval {

namespace {

std::string where(const CsvTable& t, std::size_t row) { return t.path + ":" + std::to_string(t.lines[row]); }

}  // namespace

LoopClosureMatrix loadLoopClosureImage(const std::string& path) {
  cv::Mat image;
  try {
    image = readImageFileChecked(path, ImageColor::Grey);
  } catch (const ImageReadError& e) {
    std::string reason = e.what();  // "PATH: why"
    if (reason.rfind(path + ": ", 0) == 0) reason.erase(0, path.size() + 2);
    throw RunFileError(path + ": cannot read as an image (expected a BMP/PNG loop-closure matrix): " + reason);
  }
  if (image.rows != image.cols) {
    throw RunFileError(path + ": loop-closure matrix must be square, got " + std::to_string(image.cols) +
                       "x" + std::to_string(image.rows));
  }
  LoopClosureMatrix m;
  m.size = image.rows;
  m.same.assign(static_cast<std::size_t>(m.size) * static_cast<std::size_t>(m.size), 0);
  for (int i = 0; i < m.size; ++i) {
    for (int j = 0; j < m.size; ++j) {
      if (image.at<std::uint8_t>(i, j) != 0) {
        m.same[static_cast<std::size_t>(i * m.size + j)] = 1;
        m.same[static_cast<std::size_t>(j * m.size + i)] = 1;
      }
    }
  }
  return m;
}

std::vector<NamedPair> loadLoopClosurePairs(const std::string& path) {
  const CsvTable t = readCsv(path);
  if (t.header.size() < 2) throw RunFileError(path + ":1: expected two columns: query,matches");
  std::vector<NamedPair> pairs;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string& query = t.rows[r][0];
    if (query.empty()) throw RunFileError(where(t, r) + ": empty query name");
    // The second column may itself hold several space-separated names; extra columns are more names.
    for (std::size_t c = 1; c < t.rows[r].size(); ++c) {
      std::istringstream names(t.rows[r][c]);
      std::string name;
      while (names >> name) pairs.push_back(NamedPair{query, name, t.lines[r]});
    }
  }
  return pairs;
}

}  // namespace toposlam::eval
