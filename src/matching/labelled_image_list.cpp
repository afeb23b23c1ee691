// Reads `image,label` CSV files (with RFC 4180 quoting) and quotes fields for writing: see
// labelled_image_list.hpp.
#include "toposlam/matching/labelled_image_list.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>

namespace toposlam {
namespace {

bool isSpace(unsigned char c) { return std::isspace(c) != 0; }

std::string trim(const std::string& text) {
  auto begin = std::find_if_not(text.begin(), text.end(),
                                [](char c) { return isSpace(static_cast<unsigned char>(c)); });
  auto end = std::find_if_not(text.rbegin(), text.rend(), [](char c) {
               return isSpace(static_cast<unsigned char>(c));
             }).base();
  return begin < end ? std::string(begin, end) : std::string();
}

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

/// Splits one line into fields; nullopt and `problem` set when the quoting is broken.
std::optional<std::vector<std::string>> splitFields(const std::string& text, std::string& problem) {
  std::vector<std::string> fields;
  std::size_t i = 0;
  while (true) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    std::string field;
    if (i < text.size() && text[i] == '"') {
      const std::size_t opening = i++;
      bool closed = false;
      while (i < text.size()) {
        if (text[i] == '"') {
          if (i + 1 < text.size() && text[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          closed = true;
          ++i;
          break;
        }
        field += text[i++];
      }
      if (!closed) {
        problem = "unterminated quote (opened at column " + std::to_string(opening + 1) + ")";
        return std::nullopt;
      }
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
      if (i < text.size() && text[i] != ',') {
        problem = "text after a closing quote at column " + std::to_string(i + 1) +
                  " (write a quote inside a quoted field as \"\")";
        return std::nullopt;
      }
    } else {
      const std::size_t comma = text.find(',', i);
      field = trim(text.substr(i, comma == std::string::npos ? std::string::npos : comma - i));
      if (field.find('"') != std::string::npos) {
        problem = "a double quote inside an unquoted field (quote the whole field: \"a,b.jpg\")";
        return std::nullopt;
      }
      i = comma == std::string::npos ? text.size() : comma;
    }
    fields.push_back(std::move(field));
    if (i >= text.size()) break;
    ++i;  // the comma
  }
  return fields;
}

}  // namespace

LabelledImageList readLabelledImageList(const std::string& csv_path) {
  std::ifstream in(csv_path);
  if (!in)
    throw std::runtime_error("cannot open '" + csv_path + "' (expected a CSV file of image,label lines)");
  const std::filesystem::path folder = std::filesystem::path(csv_path).parent_path();
  LabelledImageList list;
  std::string line;
  int number = 0;
  bool first_content = true;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = csv_path + ":" + std::to_string(number);
    const std::string text = trim(line);
    if (text.empty() || text.front() == '#') continue;
    std::string problem;
    const std::optional<std::vector<std::string>> parsed = splitFields(text, problem);
    const bool header = first_content && parsed && parsed->size() == 2 && lower((*parsed)[0]) == "image" &&
                        lower((*parsed)[1]) == "label";
    first_content = false;
    if (header) continue;
    if (!parsed) {
      list.problems.push_back(where + ": " + problem);
      continue;
    }
    const std::vector<std::string>& fields = *parsed;
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

std::string quoteCsvField(std::string_view field) {
  const bool needs_quotes = field.find_first_of(",\"\r\n") != std::string_view::npos ||
                            (!field.empty() && (isSpace(static_cast<unsigned char>(field.front())) ||
                                                isSpace(static_cast<unsigned char>(field.back()))));
  if (!needs_quotes) return std::string(field);
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

}  // namespace toposlam
