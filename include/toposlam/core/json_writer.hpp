// A tiny streaming JSON writer for the CLI's --json output and run folders (topology.json).
// It writes valid JSON (commas, escaping) and nothing else: no DOM, no parsing.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace toposlam {

class JsonWriter {
 public:
  explicit JsonWriter(std::ostream& out, bool pretty = true) : out_(out), pretty_(pretty) {}

  JsonWriter& beginObject();
  JsonWriter& endObject();
  JsonWriter& beginArray();
  JsonWriter& endArray();
  JsonWriter& key(std::string_view name);
  JsonWriter& value(std::string_view text);
  JsonWriter& value(const char* text) { return value(std::string_view(text)); }
  JsonWriter& value(double number);
  JsonWriter& value(std::int64_t number);
  JsonWriter& value(int number) { return value(static_cast<std::int64_t>(number)); }
  JsonWriter& value(std::size_t number) { return value(static_cast<std::int64_t>(number)); }
  JsonWriter& value(bool flag);
  JsonWriter& null();
  template <typename T>
  JsonWriter& field(std::string_view name, const T& v) { key(name); return value(v); }

  static std::string escape(std::string_view text);

 private:
  void beforeValue();
  void newline();

  std::ostream& out_;
  bool pretty_;
  struct Level { bool is_object; bool empty; };
  std::vector<Level> stack_;
  bool after_key_ = false;
};

}  // namespace toposlam
