// Small helpers shared by the `toposlam-bench ...` commands: the measured rows, in text or JSON; the timing
// samples and their summary are timing.hpp's (src/apps/common, toposlam's `segment` times itself too).
// Benchmarks print numbers; they never fail a build.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "timing.hpp"
#include "toposlam/core/json_writer.hpp"

namespace toposlam::cli {

/// The measured rows of a `toposlam-bench ...` command. Without --json the command prints its table to stdout
/// as before and the rows are not kept; with --json the table goes to stderr (for the person watching) and the
/// rows are printed at the end as one JSON object on stdout: {"benchmark": "topology", "rows": [{...}, ...]}.
class BenchRows {
 public:
  using Cell = std::variant<std::string, double, std::int64_t>;
  using Row = std::vector<std::pair<std::string, Cell>>;
  explicit BenchRows(std::string benchmark, bool json) : benchmark_(std::move(benchmark)), json_(json) {}
  BenchRows(const BenchRows&) = delete;
  BenchRows& operator=(const BenchRows&) = delete;
  ~BenchRows() { print(); }
  /// Where the table's text goes.
  std::ostream& text() const { return json_ ? std::cerr : std::cout; }
  std::FILE* textFile() const { return json_ ? stderr : stdout; }
  void row(Row cells) {
    if (json_) rows_.push_back(std::move(cells));
  }
  /// The JSON object (once; the destructor calls it).
  void print() {
    if (!json_ || printed_) return;
    printed_ = true;
    JsonWriter json(std::cout, false);
    json.beginObject().field("benchmark", benchmark_).key("rows").beginArray();
    for (const Row& r : rows_) {
      json.beginObject();
      for (const auto& [key, cell] : r) {
        json.key(key);
        if (const auto* text = std::get_if<std::string>(&cell)) json.value(*text);
        else if (const auto* number = std::get_if<double>(&cell)) json.value(*number);
        else json.value(std::get<std::int64_t>(cell));
      }
      json.endObject();
    }
    json.endArray().endObject();
    std::cout << "\n" << std::flush;
  }

 private:
  std::string benchmark_;
  bool json_;
  bool printed_ = false;
  std::vector<Row> rows_;
};

}  // namespace toposlam::cli
