// A config key's allowed values and YAML text, for every program's table (config_key.hpp).
#include "toposlam/config/config_key.hpp"

#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string configRangeNumber(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::string ConfigKeySpec::rangeText() const {
  std::string range;
  switch (kind) {
    case ConfigKind::Integer:
      range = std::to_string(integer_low) + " .. " + std::to_string(integer_high);
      break;
    case ConfigKind::Real:
      range = std::string(low_open ? "(" : "[") + configRangeNumber(low) + ", " + configRangeNumber(high) +
              (high_open ? ")" : "]");
      break;
    case ConfigKind::Flag:
      range = "true or false";
      break;
    case ConfigKind::Text:
      range = std::to_string(min_length) + " to " + std::to_string(max_length) + " characters";
      break;
    case ConfigKind::Choice:
      for (const std::string& c : choices) range += (range.empty() ? "one of: " : ", ") + c;
      break;
  }
  if (!unit.empty()) range += " " + unit;
  if (!note.empty()) range += " (" + note + ")";
  return range;
}

std::string ConfigKeySpec::problem(const ConfigValue& value) const {
  switch (kind) {
    case ConfigKind::Integer: {
      const long long v = std::get<long long>(value);
      if (v >= integer_low && v <= integer_high) return "";
      return std::to_string(v) + " is out of range, allowed " + rangeText();
    }
    case ConfigKind::Real: {
      const double v = std::get<double>(value);
      const bool inside =
          std::isfinite(v) && (low_open ? v > low : v >= low) && (high_open ? v < high : v <= high);
      if (inside) return "";
      return configRangeNumber(v) + " is out of range, allowed " + rangeText();
    }
    case ConfigKind::Flag:
      return "";
    case ConfigKind::Text: {
      const std::string& v = std::get<std::string>(value);
      if (v.size() >= min_length && v.size() <= max_length) return "";
      if (v.empty() && !example.empty()) return "must not be empty (e.g. " + example + ")";
      return "must have " + std::to_string(min_length) + " to " + std::to_string(max_length) +
             " characters, got '" + v + "'";
    }
    case ConfigKind::Choice: {
      const std::string& v = std::get<std::string>(value);
      for (const std::string& c : choices)
        if (c == v) return "";
      std::string list;
      for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
      return "'" + v + "' is not allowed, expected one of: " + list;
    }
  }
  return "";
}

std::string ConfigKeySpec::yamlText(const ConfigValue& value) const {
  switch (kind) {
    case ConfigKind::Integer:
      return std::to_string(std::get<long long>(value));
    case ConfigKind::Real: {
      char buffer[64];
      const auto result = std::to_chars(buffer, buffer + sizeof buffer, std::get<double>(value));
      std::string text(buffer, result.ptr);
      // A real reads as a real: "5" would too, but "5.0" says what the key is; "1e+06" reads back exactly.
      if (text.find_first_of(".en") == std::string::npos) text += ".0";
      return text;
    }
    case ConfigKind::Flag:
      return std::get<bool>(value) ? "true" : "false";
    case ConfigKind::Choice:
      return std::get<std::string>(value);
    case ConfigKind::Text: {
      std::string quoted = "\"";
      for (const char ch : std::get<std::string>(value)) {
        if (ch == '"' || ch == '\\') quoted += '\\';
        quoted += ch;
      }
      return quoted + "\"";
    }
  }
  return "";
}

double ConfigKeySpec::defaultNumber() const {
  if (kind == ConfigKind::Integer) return static_cast<double>(std::get<long long>(default_value));
  if (kind == ConfigKind::Real) return std::get<double>(default_value);
  throw std::logic_error("config key " + path + " is not a number");
}

}  // namespace toposlam
