// The project's CSV reader and writer: see csv.hpp.
#include "toposlam/core/csv.hpp"

#include <algorithm>
#include <string>

namespace toposlam {
namespace {

/// White space a reader trims around unquoted fields ('\n' only occurs inside quoted fields).
bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view text) {
  std::size_t begin = 0, end = text.size();
  while (begin < end && isBlank(text[begin])) ++begin;
  while (end > begin && isBlank(text[end - 1])) --end;
  return text.substr(begin, end - begin);
}

/// "column C" of position `at` in `text`, with "line L, " before it when the text spans lines (its first
/// line being line `first_line` of the file).
std::string position(std::string_view text, std::size_t at, int first_line) {
  std::size_t line = static_cast<std::size_t>(first_line), line_start = 0;
  for (std::size_t i = 0; i < at && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  std::string where = "column " + std::to_string(at - line_start + 1);
  if (text.find('\n') != std::string_view::npos) where = "line " + std::to_string(line) + ", " + where;
  return where;
}

/// True while `text` ends inside a quoted field (quotes counted; a doubled quote counts twice).
bool quoteOpen(std::string_view text) {
  bool open = false;
  for (char c : text) open = c == '"' ? !open : open;
  return open;
}

}  // namespace

std::vector<std::string> splitCsvRecord(std::string_view text, std::string& problem, int first_line) {
  problem.clear();
  std::vector<std::string> fields;
  std::size_t i = 0;
  while (true) {
    while (i < text.size() && isBlank(text[i])) ++i;
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
        problem = "unterminated quote (opened at " + position(text, opening, first_line) +
                  (text.find('\n') != std::string_view::npos ? "; the quoted field runs to the end of the file)" : ")");
        return {};
      }
      while (i < text.size() && isBlank(text[i])) ++i;
      if (i < text.size() && text[i] != ',') {
        problem = "text after a closing quote at " + position(text, i, first_line) +
                  " (write a quote inside a quoted field as \"\")";
        return {};
      }
    } else {
      const std::size_t comma = std::min(text.find(',', i), text.size());
      const std::string_view unquoted = trim(text.substr(i, comma - i));
      if (const std::size_t quote = unquoted.find('"'); quote != std::string_view::npos) {
        problem = "a double quote inside an unquoted field at " +
                  position(text, static_cast<std::size_t>(unquoted.data() - text.data()) + quote, first_line) +
                  " (quote the whole field and double the quote: \"say \"\"hi\"\"\")";
        return {};
      }
      field = std::string(unquoted);
      i = comma;
    }
    fields.push_back(std::move(field));
    if (i >= text.size()) break;
    ++i;  // the comma
  }
  return fields;
}

CsvReader::CsvReader(std::istream& in, CsvReadOptions options) : in_(in), options_(options) {}

bool CsvReader::nextLine(std::string& line) {
  if (!std::getline(in_, line)) return false;
  ++line_number_;
  return true;
}

bool CsvReader::next(CsvRecord& record) {
  std::string line;
  while (nextLine(line)) {
    const std::string_view content = trim(line);
    if (content.empty() || (options_.comments && content.front() == '#')) continue;
    record.line = line_number_;
    record.text = std::move(line);
    if (options_.quoted_line_breaks) {
      while (quoteOpen(record.text) && nextLine(line)) {
        record.text += '\n';
        record.text += line;
      }
    }
    // CRLF: the record's line end. A '\r' before a line break inside a quoted field is the field's own.
    if (!record.text.empty() && record.text.back() == '\r') record.text.pop_back();
    record.fields = splitCsvRecord(record.text, record.problem, record.line);
    return true;
  }
  return false;
}

std::string quoteCsvField(std::string_view field) {
  const bool needs_quotes = field.find_first_of(",\"\r\n") != std::string_view::npos ||
                            (!field.empty() && (isBlank(field.front()) || isBlank(field.back())));
  if (!needs_quotes) return std::string(field);
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string csvRecordText(const std::vector<std::string>& fields) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) out += ',';
    out += quoteCsvField(fields[i]);
  }
  return out;
}

}  // namespace toposlam
