// The project's CSV reader and writer (core/csv.hpp): RFC 4180 quoting, CRLF, blank lines, comments,
// records spanning lines, and broken quoting reported with its line and column.
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "toposlam/core/csv.hpp"

using toposlam::CsvReader;
using toposlam::CsvReadOptions;
using toposlam::CsvRecord;
using toposlam::quoteCsvField;

namespace {

std::vector<CsvRecord> readAll(const std::string& text, CsvReadOptions options = {}) {
  std::istringstream in(text);
  CsvReader reader(in, options);
  std::vector<CsvRecord> records;
  for (CsvRecord record; reader.next(record);) records.push_back(record);
  return records;
}

using Fields = std::vector<std::string>;

}  // namespace

SCENARIO("GIVEN csv text with quotes, embedded commas and quotes WHEN read THEN the fields are exact", "[core][csv]") {
  const auto records = readAll("name,value\n\"a,b\",\"say \"\"hi\"\"\"\n  plain  , \"  kept  \" \n");
  REQUIRE(records.size() == 3);
  CHECK(records[0].fields == Fields{"name", "value"});
  CHECK(records[1].fields == Fields{"a,b", "say \"hi\""});
  CHECK(records[1].line == 2);
  CHECK(records[2].fields == Fields{"plain", "  kept  "});
  CHECK(records[2].problem.empty());
}

SCENARIO("GIVEN csv text with CRLF line ends and blank lines WHEN read THEN they are neither in fields nor records",
         "[core][csv]") {
  const auto records = readAll("a,\"b\"\r\n\r\n   \r\nc,d\r\n");
  REQUIRE(records.size() == 2);
  CHECK(records[0].fields == Fields{"a", "b"});
  CHECK(records[1].fields == Fields{"c", "d"});
  CHECK(records[1].line == 4);
  CHECK(records[1].text == "c,d");
}

SCENARIO("GIVEN csv records with empty fields WHEN read THEN every empty field is kept", "[core][csv]") {
  const auto records = readAll(",x,,\n\"\"\n");
  REQUIRE(records.size() == 2);
  CHECK(records[0].fields == Fields{"", "x", "", ""});
  CHECK(records[1].fields == Fields{""});
}

SCENARIO("GIVEN a csv quoted field holding line breaks WHEN read THEN it is one record starting at its first line",
         "[core][csv]") {
  const auto records = readAll("h\n\"two\r\nlines\",x\r\nnext,y\n");
  REQUIRE(records.size() == 3);
  CHECK(records[1].fields == Fields{"two\r\nlines", "x"});  // the field's own CRLF is kept
  CHECK(records[1].line == 2);
  CHECK(records[2].fields == Fields{"next", "y"});
  CHECK(records[2].line == 4);
}

SCENARIO("GIVEN a truncated csv file ending inside a quote WHEN read THEN the record names the line it opened at",
         "[core][csv]") {
  const auto records = readAll("h,i\n1,2\n3,\"unterminated\n4,5\n");
  REQUIRE(records.size() == 3);
  CHECK(records[2].line == 3);
  CHECK(records[2].fields.empty());
  CHECK(records[2].problem ==
        "unterminated quote (opened at line 3, column 3; the quoted field runs to the end of the file)");
}

SCENARIO("GIVEN broken csv quoting, one record per line WHEN read THEN each bad line says what and where",
         "[core][csv]") {
  CsvReadOptions per_line;
  per_line.quoted_line_breaks = false;
  per_line.comments = true;
  const auto records = readAll("# comment\n\"open,x\n\"a\"x,y\nbad\"quote,z\nfine,w\n", per_line);
  REQUIRE(records.size() == 4);
  CHECK(records[0].line == 2);
  CHECK(records[0].problem == "unterminated quote (opened at column 1)");
  CHECK(records[1].problem == "text after a closing quote at column 4 (write a quote inside a quoted field as \"\")");
  CHECK_THAT(records[2].problem, Catch::StartsWith("a double quote inside an unquoted field at column 4"));
  CHECK(records[3].fields == Fields{"fine", "w"});
}

SCENARIO("GIVEN csv fields WHEN quoted and read back THEN only fields that need it are quoted and all are exact",
         "[core][csv]") {
  CHECK(quoteCsvField("plain.jpg") == "plain.jpg");
  CHECK(quoteCsvField("a,b.jpg") == "\"a,b.jpg\"");
  CHECK(quoteCsvField("say \"hi\"") == "\"say \"\"hi\"\"\"");
  CHECK(quoteCsvField(" edge") == "\" edge\"");
  CHECK(quoteCsvField("") == "");
  const Fields fields{"a,b", "say \"hi\"", " edge ", "", "two\nlines", "cr\r\nlf", "plain"};
  const auto records = readAll(toposlam::csvRecordText(fields) + "\r\n");
  REQUIRE(records.size() == 1);
  CHECK(records[0].fields == fields);
}
