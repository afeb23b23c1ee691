// Frame-source URI parsing and typed query getters (source_uri.hpp).
#include "toposlam/io/source_uri.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

namespace {

[[noreturn]] void fail(const SourceUri& uri, const std::string& message) {
  throw FrameSourceError("source '" + uri.text + "': " + message);
}

bool isSchemeChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-';
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string current;
  for (char c : text) {
    if (c == separator) {
      parts.push_back(current);
      current.clear();
    } else {
      current.push_back(c);
    }
  }
  parts.push_back(current);
  return parts;
}

/// True when every '&'-separated item has the form key=value.
bool looksLikeQuery(const std::string& text) {
  if (text.empty()) return false;
  for (const std::string& item : split(text, '&')) {
    const auto equals = item.find('=');
    if (equals == std::string::npos || equals == 0) return false;
  }
  return true;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

}  // namespace

SourceUri parseSourceUri(const std::string& text) {
  SourceUri uri;
  uri.text = text;
  if (text.empty()) throw FrameSourceError("source: empty URI; expected e.g. images:DIR, video:FILE or sim:office");
  std::string rest = text;
  const auto colon = text.find(':');
  if (colon != std::string::npos && colon > 1 &&
      std::all_of(text.begin(), text.begin() + static_cast<long>(colon), isSchemeChar)) {
    uri.scheme = lower(text.substr(0, colon));
    rest = text.substr(colon + 1);
  }
  const auto question = rest.rfind('?');
  if (question != std::string::npos && (question + 1 == rest.size() || looksLikeQuery(rest.substr(question + 1)))) {
    for (const std::string& item : split(rest.substr(question + 1), '&')) {
      if (item.empty()) continue;
      const auto equals = item.find('=');
      const std::string key = item.substr(0, equals);
      if (uri.query.count(key) != 0) fail(uri, "query key '" + key + "' given twice");
      uri.query[key] = item.substr(equals + 1);
    }
    rest = rest.substr(0, question);
  }
  uri.path = rest;
  return uri;
}

std::string SourceUri::getString(const std::string& key, const std::string& fallback) const {
  const auto found = query.find(key);
  return found == query.end() ? fallback : found->second;
}

std::string SourceUri::getChoice(const std::string& key, const std::string& fallback,
                                 const std::vector<std::string>& allowed) const {
  const std::string value = getString(key, fallback);
  if (std::find(allowed.begin(), allowed.end(), value) != allowed.end()) return value;
  std::string list;
  for (const std::string& option : allowed) list += (list.empty() ? "" : ", ") + option;
  fail(*this, key + "=" + value + " is not allowed; allowed: " + list);
}

double SourceUri::getDouble(const std::string& key, double fallback, double min_value, double max_value) const {
  const auto found = query.find(key);
  if (found == query.end()) return fallback;
  const std::string& text_value = found->second;
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text_value.c_str(), &end);
  std::ostringstream range;
  range << "a number in " << min_value << ".." << max_value;
  if (text_value.empty() || end != text_value.c_str() + text_value.size() || errno != 0 || !std::isfinite(value)) {
    fail(*this, key + "=" + text_value + " is not a number; expected " + range.str());
  }
  if (value < min_value || value > max_value) fail(*this, key + "=" + text_value + " is out of range; expected " + range.str());
  return value;
}

long long SourceUri::getInt(const std::string& key, long long fallback, long long min_value, long long max_value) const {
  const auto found = query.find(key);
  if (found == query.end()) return fallback;
  const std::string& text_value = found->second;
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(text_value.c_str(), &end, 10);
  const std::string range = "a whole number in " + std::to_string(min_value) + ".." + std::to_string(max_value);
  if (text_value.empty() || end != text_value.c_str() + text_value.size() || errno != 0) {
    fail(*this, key + "=" + text_value + " is not a whole number; expected " + range);
  }
  if (value < min_value || value > max_value) fail(*this, key + "=" + text_value + " is out of range; expected " + range);
  return value;
}

bool SourceUri::getBool(const std::string& key, bool fallback) const {
  const auto found = query.find(key);
  if (found == query.end()) return fallback;
  const std::string value = lower(found->second);
  if (value == "1" || value == "true" || value == "yes" || value == "on") return true;
  if (value == "0" || value == "false" || value == "no" || value == "off") return false;
  fail(*this, key + "=" + found->second + " is not a switch; allowed: 1, 0, true, false, yes, no, on, off");
}

std::pair<int, int> SourceUri::getSize(const std::string& key, std::pair<int, int> fallback, int min_side,
                                       int max_side) const {
  const auto found = query.find(key);
  if (found == query.end()) return fallback;
  const std::string& value = found->second;
  const std::string expected = "expected WxH with each side in " + std::to_string(min_side) + ".." +
                               std::to_string(max_side) + ", e.g. 320x240";
  const auto x = lower(value).find('x');
  if (x == std::string::npos || x == 0 || x + 1 == value.size()) fail(*this, key + "=" + value + ": " + expected);
  const std::string w = value.substr(0, x), h = value.substr(x + 1);
  auto digits = [](const std::string& s) { return std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }); };
  if (!digits(w) || !digits(h) || w.size() > 6 || h.size() > 6) fail(*this, key + "=" + value + ": " + expected);
  const int width = std::stoi(w), height = std::stoi(h);
  if (width < min_side || width > max_side || height < min_side || height > max_side) {
    fail(*this, key + "=" + value + ": " + expected);
  }
  return {width, height};
}

void SourceUri::requireOnly(const std::vector<std::string>& allowed) const {
  for (const auto& [key, value] : query) {
    if (key == "rate" || std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string list;
    for (const std::string& option : allowed) list += option + ", ";
    list += "rate";
    fail(*this, "unknown query key '" + key + "'" + (scheme.empty() ? "" : " for " + scheme + ":") + "; allowed: " + list);
  }
}

std::string absoluteSourceUri(const std::string& uri) {
  const SourceUri parsed = parseSourceUri(uri);
  if (!parsed.scheme.empty() && parsed.scheme != "images" && parsed.scheme != "video") return uri;
  const std::size_t path_start = parsed.scheme.empty() ? 0 : parsed.scheme.size() + 1;
  const std::string query = uri.substr(std::min(uri.size(), path_start + parsed.path.size()));
  const std::string prefix = parsed.scheme.empty() ? "" : parsed.scheme + ":";
  return prefix + std::filesystem::absolute(parsed.path).lexically_normal().string() + query;
}

std::string sourceIdentity(const std::string& uri) {
  const SourceUri parsed = parseSourceUri(uri);
  if (parsed.scheme.empty() || parsed.scheme == "images" || parsed.scheme == "video")
    return (parsed.scheme.empty() ? std::string("images") : parsed.scheme) + ":" +
           std::filesystem::absolute(parsed.path).lexically_normal().string();
  return parsed.scheme + ":" + parsed.path;
}

}  // namespace toposlam
