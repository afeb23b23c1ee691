// The HTML report's pure parts: base64, thumbnail choice and the page's structure (no browser here; the
// browser check is tests/apps/check_report_in_browser.sh).
#include <catch2/catch.hpp>

#include "eval_fixture.hpp"
#include "toposlam/eval/report.hpp"

using namespace toposlam;
using namespace toposlam::eval;
using namespace toposlam::eval::testing;
using Catch::Matchers::Contains;

namespace {
int countOf(const std::string& text, const std::string& needle) {
  int n = 0;
  for (auto pos = text.find(needle); pos != std::string::npos; pos = text.find(needle, pos + 1)) ++n;
  return n;
}
}  // namespace

SCENARIO("GIVEN byte strings of length 3, 2, 1 and 0 WHEN base64-encoded THEN they match RFC 4648") {
  CHECK(base64Encode({'M', 'a', 'n'}) == "TWFu");
  CHECK(base64Encode({'M', 'a'}) == "TWE=");
  CHECK(base64Encode({'M'}) == "TQ==");
  CHECK(base64Encode({}).empty());
  CHECK(base64Encode({0xff, 0xfe, 0xfd, 0x00}) == "//79AA==");
}

SCENARIO(
    "GIVEN the fixture run WHEN the report is rendered THEN every figure and one <img> per thumbnail are "
    "inline") {
  const auto dir = writeFixtureRun("report");
  ReportInputs in;
  in.title = "fixture";
  in.run = loadRun(dir.string());
  in.eval = evaluate(in.run, loadTruth((dir / "labels.csv").string()), EvalOptions{});
  for (const auto& l : loadLabels((dir / "labels.csv").string())) in.rooms.push_back(l.room);
  const std::vector<std::int64_t> wanted = framesForThumbnails(in.run, 5);
  CHECK(wanted ==
        std::vector<std::int64_t>{0, 1, 2, 4, 6, 7, 8});  // every 2nd frame plus representatives 1, 4, 7
  in.thumbnails.assign(10, "");
  const std::string pixel =
      "data:image/"
      "png;base64,"
      "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8DwHwAFBQIAX8jx0gAAAABJRU5ErkJggg==";
  for (std::int64_t f : wanted) in.thumbnails[static_cast<std::size_t>(f)] = pixel;
  in.run.places[1].end = "doorway";  // the fixture's places.csv predates the column: "-" for the others
  in.run.places[2].end = "<b>";      // a damaged file's text is shown as text
  in.generator = "toposlam 9.9.9";
  in.generated = "2026-12-02 10:00 UTC";
  in.pictures.emplace_back("floor plan and route", pixel);
  const std::string html = renderReportHtml(in);
  CHECK_THAT(html, Contains("<!DOCTYPE html>"));
  // Header: what the run was made from and with (the fixture has neither source.txt nor settings.txt).
  CHECK_THAT(html, Contains("<caption>Run</caption>"));
  CHECK_THAT(html, Contains("not recorded (no source.txt in the run folder)"));
  CHECK_THAT(html, Contains("<td style=\"text-align:left\">toposlam 9.9.9</td>"));
  CHECK_THAT(html, Contains("2026-12-02 10:00 UTC"));
  // Legends, node-by-room frames, places with their representatives, the simulator's picture.
  CHECK_THAT(html, Contains("true rooms:"));
  CHECK_THAT(html, Contains("Frames per node (rows) and true room"));
  CHECK_THAT(html, Contains("<h2>Places and their representatives</h2>"));
  CHECK_THAT(html, Contains("<th>ended by</th>"));
  CHECK_THAT(html, Contains("</td><td>-</td>"));
  CHECK_THAT(html, Contains("</td><td>doorway</td>"));
  CHECK_THAT(html, Contains("</td><td>&lt;b&gt;</td>"));
  CHECK_THAT(html, Contains("<figcaption>floor plan and route</figcaption>"));
  CHECK_THAT(html, Contains("<p id=\"image-check\" hidden>"));
  CHECK_THAT(html, Contains("Figure 4.10"));
  CHECK_THAT(html, Contains("Figure 5.4"));
  CHECK_THAT(html, Contains("Figures 5.6/5.7"));
  CHECK_THAT(html, Contains("node 1<br>places 1"));
  CHECK_THAT(html, Contains("id=\"image-check\""));
  CHECK_THAT(html, Contains("true room"));
  CHECK_THAT(html, Contains("recall at 100% precision"));
  // Strip: every frame (n = 10 <= 96 thumbnails); topology: one per node; places: one per representative;
  // the picture.
  CHECK(countOf(html, "<img ") == 7 + 2 + 3 + 1);
  CHECK(countOf(html, "<svg") >= 6);  // 2 strips, lambda2, topology, probability, timing, PR curve
  CHECK(html.find("src=\"http") == std::string::npos);
  CHECK(html.find("src=\"file") == std::string::npos);
  const auto figures = renderReportFigures(in);
  CHECK(figures.size() == 7);  // strip, rooms, lambda2, topology, probability, timing, precision_recall
  REQUIRE(figures.count("topology.svg") == 1);
  CHECK(countOf(figures.at("topology.svg"), "<image ") == 2);
  CHECK_THAT(figures.at("lambda2.svg"), Contains("<svg"));
  CHECK(indexColour(-1) == "#bbbbbb");
  CHECK(indexColour(0) != indexColour(1));
}
