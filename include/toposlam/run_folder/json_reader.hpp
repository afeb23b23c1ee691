// A small, tolerant JSON reader for the run folders' topology.json (and eval.json in tests). It builds a
// plain value tree; errors name the source (file name), the line and the column. Numbers are doubles;
// NaN/Infinity literals (which some writers emit) are accepted as numbers. No streaming, no comments.
//
// Thread-safety: parseJson is a pure function; JsonValue is a plain value type.
#pragma once

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace toposlam {

/// Thrown for malformed JSON or a value of the wrong type; what() names the source and position.
class JsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JsonValue {
 public:
  enum class Type { Null, Bool, Number, String, Array, Object };

  JsonValue() = default;
  static JsonValue makeBool(bool b);
  static JsonValue makeNumber(double n);
  static JsonValue makeString(std::string s);
  static JsonValue makeArray(std::vector<JsonValue> items);
  static JsonValue makeObject(std::map<std::string, JsonValue> members);

  Type type() const { return type_; }
  bool isNull() const { return type_ == Type::Null; }
  bool isNumber() const { return type_ == Type::Number; }
  bool isArray() const { return type_ == Type::Array; }
  bool isObject() const { return type_ == Type::Object; }

  /// Typed access; throws JsonError("<what>: expected a number") etc. `what` names the field for the message.
  double asNumber(std::string_view what = "value") const;
  bool asBool(std::string_view what = "value") const;
  const std::string& asString(std::string_view what = "value") const;
  const std::vector<JsonValue>& asArray(std::string_view what = "value") const;
  const std::map<std::string, JsonValue>& asObject(std::string_view what = "value") const;

  /// Member of an object, nullptr when absent (or when this is not an object).
  const JsonValue* find(const std::string& key) const;
  /// Member of an object; throws JsonError("missing key '<key>'") when absent.
  const JsonValue& at(const std::string& key) const;

 private:
  Type type_ = Type::Null;
  bool bool_ = false;
  double number_ = 0.0;
  std::string string_;
  std::vector<JsonValue> array_;
  std::map<std::string, JsonValue> object_;
};

/// Parses a whole document. `source_name` (e.g. the file path) prefixes every error message:
/// "<source>:<line>:<column>: <problem>".
JsonValue parseJson(std::string_view text, const std::string& source_name = "json");

/// Reads and parses a file; throws JsonError naming the file when it cannot be read or parsed.
JsonValue readJsonFile(const std::string& path);

}  // namespace toposlam
