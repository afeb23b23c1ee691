// Reads `image,label` CSV files: see labelled_image_list.hpp.
#include "toposlam/matching/labelled_image_list.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace toposlam {
namespace {

std::string trim(const std::string& text) {
  auto is_space = [](unsigned char c) { return std::isspace(c) != 0; };
  auto begin = std::find_if_not(text.begin(), text.end(), is_space);
  auto end = std::find_if_not(text.rbegin(), text.rend(), is_space).base();
  return begin < end ? std::string(begin, end) : std::string();
}

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

}  // namespace

LabelledImageList readLabelledImageList(const std::string& csv_path) {
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error("cannot open '" + csv_path + "' (expected a CSV file of image,label lines)");
  const std::filesystem::path folder = std::filesystem::path(csv_path).parent_path();
  LabelledImageList list;
  std::string line;
  int number = 0;
  bool first_content = true;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = csv_path + ":" + std::to_string(number);
    std::string text = trim(line);
    if (text.empty() || text.front() == '#') continue;
    std::vector<std::string> fields;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = text.find(',', start);
      fields.push_back(trim(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    const bool header = first_content && fields.size() == 2 && lower(fields[0]) == "image" && lower(fields[1]) == "label";
    first_content = false;
    if (header) continue;
    if (fields.size() != 2) {
      list.problems.push_back(where + ": expected 2 fields 'image,label', found " + std::to_string(fields.size()));
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
