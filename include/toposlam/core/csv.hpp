// The project's one CSV reader and writer, for every CSV file it reads or writes (run folders, ground
// truth, labelled image lists, motion logs).
//
// The dialect is RFC 4180 with a few allowances for files edited by hand: a field in double quotes may
// hold commas, line breaks and quotes written twice ("say ""hi"""); white space around a field is
// ignored unless it is quoted; a record may end in CRLF; blank lines are skipped. Broken quoting (a quote
// left open, text after a closing quote, a quote inside an unquoted field) is reported per record with the
// line and column, so the caller can name the file and skip the record or refuse the file.
//
// Thread-safety: a CsvReader is used from one thread; the functions are reentrant.
#pragma once

#include <istream>
#include <string>
#include <string_view>
#include <vector>

namespace toposlam {

/// One record of a CSV file.
struct CsvRecord {
  std::vector<std::string> fields;  ///< empty when `problem` is set
  int line = 0;                     ///< line of the file where the record starts, from 1
  /// Empty, or what is wrong with the record's quoting, e.g. "unterminated quote (opened at column 3)".
  std::string problem;
  /// The record as read: its lines joined by '\n' (a CRLF inside a quoted field stays "\r\n", the field's
  /// own line break), without the '\r' of a CRLF at its end.
  std::string text;
};

struct CsvReadOptions {
  /// RFC 4180: a quoted field may hold line breaks, so a record may span lines. Off: every line is a
  /// record of its own, and a quote still open at its end is an unterminated quote on that line.
  bool quoted_line_breaks = true;
  /// Skip lines whose first character other than white space is '#'.
  bool comments = false;
};

/// Reads records from a stream, one at a time.
class CsvReader {
 public:
  explicit CsvReader(std::istream& in, CsvReadOptions options = {});
  /// The next record that is not blank (nor a comment); false at the end of the input. A record with
  /// broken quoting comes back with `problem` set: the caller reports it as "<file>:<line>: <problem>".
  bool next(CsvRecord& record);

 private:
  bool nextLine(std::string& line);

  std::istream& in_;
  CsvReadOptions options_;
  int line_number_ = 0;
};

/// The fields of one record's text (lines joined by '\n'), or none and `problem` set when its quoting is
/// broken. The problem names the column, and the file's line when the text spans several (its first line
/// being line `first_line` of the file).
std::vector<std::string> splitCsvRecord(std::string_view text, std::string& problem, int first_line = 1);

/// `field` as written in a CSV file: in double quotes with inner quotes doubled when it holds a comma, a
/// quote or a line break, or starts or ends with white space (which a reader would trim); else as it is.
std::string quoteCsvField(std::string_view field);

/// The fields quoted as needed and joined by commas (no line end).
std::string csvRecordText(const std::vector<std::string>& fields);

}  // namespace toposlam
