// Tests of readLabelledImageList and quoteCsvField: the `image,label` CSV files of `toposlam localize`
// (bad lines reported with their line number and skipped; paths with commas quoted).
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "toposlam/matching/labelled_image_list.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

fs::path writeCsv(const std::string& name, const std::string& content) {
  const fs::path dir =
      fs::path(TOPOSLAM_BINARY_DIR) / "test-output" / "matching" / ("labelled-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path path = dir / name;
  std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
  return path;
}

}  // namespace

SCENARIO("GIVEN a CSV with good and bad lines WHEN read THEN bad lines are reported by number and skipped") {
  const fs::path csv = writeCsv("mixed.csv",
                                "image,label\n"           // 1 header
                                "a.jpg,kitchen\n"         // 2 good
                                "\n"                      // 3 blank
                                "# a comment\n"           // 4 comment
                                "b.jpg\n"                 // 5 one field
                                "c.jpg,hall,extra\n"      // 6 three fields
                                ",hall\n"                 // 7 empty path
                                "d.jpg,\n"                // 8 empty label
                                "  sub/e.jpg , hall  \n"  // 9 good, trimmed
                                "/abs/f.jpg,office\n");   // 10 good, absolute
  const LabelledImageList list = readLabelledImageList(csv.string());
  const std::string folder = csv.parent_path().string();
  THEN("the three good lines are kept with resolved paths and their source line") {
    REQUIRE(list.images.size() == 3);
    CHECK(list.images[0].path == folder + "/a.jpg");
    CHECK(list.images[0].label == "kitchen");
    CHECK(list.images[0].source == csv.string() + ":2");
    CHECK(list.images[1].path == folder + "/sub/e.jpg");
    CHECK(list.images[1].label == "hall");
    CHECK(list.images[1].source == csv.string() + ":9");
    CHECK(list.images[2].path == "/abs/f.jpg");
  }
  THEN("each of the four bad lines is reported as file:line with what is wrong") {
    REQUIRE(list.problems.size() == 4);
    CHECK(list.problems[0] == csv.string() + ":5: expected 2 fields 'image,label', found 1");
    CHECK_THAT(list.problems[1],
               Catch::StartsWith(csv.string() + ":6: expected 2 fields 'image,label', found 3") &&
                   Catch::Contains("quote a path holding a comma"));
    CHECK(list.problems[2] == csv.string() + ":7: empty image path");
    CHECK(list.problems[3] == csv.string() + ":8: empty label");
  }
}

SCENARIO("GIVEN paths with commas and quotes WHEN quoted and read back THEN they are exact") {
  for (const std::string path : {"plain.jpg", "a,b.jpg", "say \"hi\".jpg", " padded .jpg", "x,\"y\",z.jpg"}) {
    const std::string label = "place, one";
    const fs::path csv =
        writeCsv("quoted.csv", "image,label\n" + quoteCsvField(path) + "," + quoteCsvField(label) + "\n");
    const LabelledImageList list = readLabelledImageList(csv.string());
    INFO("path " << path << " written as " << quoteCsvField(path));
    REQUIRE(list.problems.empty());
    REQUIRE(list.images.size() == 1);
    CHECK(list.images[0].path == (csv.parent_path() / path).lexically_normal().string());
    CHECK(list.images[0].label == label);
  }
  THEN("only fields that need it are quoted") {
    CHECK(quoteCsvField("plain.jpg") == "plain.jpg");
    CHECK(quoteCsvField("a,b.jpg") == "\"a,b.jpg\"");
    CHECK(quoteCsvField("say \"hi\"") == "\"say \"\"hi\"\"\"");
    CHECK(quoteCsvField("") == "");
  }
}

SCENARIO("GIVEN broken quoting WHEN read THEN the line is reported and the others are kept") {
  const fs::path csv = writeCsv("broken.csv",
                                "\"open.jpg,place\n"        // 1 unterminated
                                "\"a.jpg\"x,place\n"        // 2 text after the closing quote
                                "bad\"quote.jpg,place\n"    // 3 quote inside an unquoted field
                                "\"ok,1.jpg\" , place\n");  // 4 good
  const LabelledImageList list = readLabelledImageList(csv.string());
  REQUIRE(list.problems.size() == 3);
  CHECK_THAT(list.problems[0], Catch::StartsWith(csv.string() + ":1: unterminated quote"));
  CHECK_THAT(list.problems[1], Catch::StartsWith(csv.string() + ":2: text after a closing quote"));
  CHECK_THAT(list.problems[2],
             Catch::StartsWith(csv.string() + ":3: a double quote inside an unquoted field"));
  REQUIRE(list.images.size() == 1);
  CHECK(list.images[0].path == (csv.parent_path() / "ok,1.jpg").string());
  CHECK(list.images[0].label == "place");
  CHECK(list.images[0].source == csv.string() + ":4");
}

SCENARIO("GIVEN a CSV that does not exist WHEN read THEN the error names it") {
  CHECK_THROWS_WITH(readLabelledImageList("/nonexistent/places.csv"),
                    Catch::Contains("cannot open '/nonexistent/places.csv'"));
}
