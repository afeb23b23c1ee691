// Reads `image,label` CSV files (through the project's CSV reader, one record per line): see
// labelled_image_list.hpp.
#include "toposlam/matching/labelled_image_list.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "toposlam/core/csv.hpp"

namespace toposlam {
namespace {

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

}  // namespace

LabelledImageList readLabelledImageList(const std::string& csv_path) {
  std::ifstream in(csv_path);
  if (!in)
    throw std::runtime_error("cannot open '" + csv_path + "' (expected a CSV file of image,label lines)");
  const std::filesystem::path folder = std::filesystem::path(csv_path).parent_path();
  LabelledImageList list;
  // One record per line: a bad line is reported and skipped, the next one read on its own.
  CsvReadOptions options;
  options.quoted_line_breaks = false;
  options.comments = true;
  CsvReader reader(in, options);
  bool first_content = true;
  for (CsvRecord record; reader.next(record);) {
    const std::string where = csv_path + ":" + std::to_string(record.line);
    const std::vector<std::string>& fields = record.fields;
    const bool header = first_content && record.problem.empty() && fields.size() == 2 &&
                        lower(fields[0]) == "image" && lower(fields[1]) == "label";
    first_content = false;
    if (header) continue;
    if (!record.problem.empty()) {
      list.problems.push_back(where + ": " + record.problem);
      continue;
    }
    if (fields.size() != 2) {
      list.problems.push_back(where + ": expected 2 fields 'image,label', found " +
                              std::to_string(fields.size()) +
                              (fields.size() > 2 ? " (quote a path holding a comma: \"a,b.jpg\")" : ""));
      continue;
    }
    if (fields[0].empty() || fields[1].empty()) {
      list.problems.push_back(where + ": empty " + std::string(fields[0].empty() ? "image path" : "label"));
      continue;
    }
    std::filesystem::path image(fields[0]);
    if (image.is_relative()) image = folder / image;
    list.images.push_back({image.lexically_normal().string(), fields[1], where});
  }
  return list;
}

}  // namespace toposlam
