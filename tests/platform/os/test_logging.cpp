// Logging set-up (platform/os): --log-level names, sd-daemon priorities, the journal-stream check and the
// two line formats.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include <spdlog/details/log_msg.h>

#include "toposlam/platform/logging.hpp"

using namespace toposlam;

namespace {

std::string formatted(bool journal, spdlog::level::level_enum level, const char* text) {
  const auto formatter = makeLogFormatter(journal);
  const spdlog::details::log_msg message("toposlamd", level, text);
  spdlog::memory_buf_t out;
  formatter->format(message, out);
  return std::string(out.data(), out.size());
}

}  // namespace

TEST_CASE("GIVEN the --log-level names WHEN parsed THEN each is its spdlog level and others are refused", "[logging]") {
  CHECK(parseLogLevel("trace") == spdlog::level::trace);
  CHECK(parseLogLevel("debug") == spdlog::level::debug);
  CHECK(parseLogLevel("info") == spdlog::level::info);
  CHECK(parseLogLevel("warn") == spdlog::level::warn);
  CHECK(parseLogLevel("error") == spdlog::level::err);
  CHECK_FALSE(parseLogLevel("warning").has_value());
  CHECK_FALSE(parseLogLevel("").has_value());
  CHECK_FALSE(parseLogLevel("INFO").has_value());
}

TEST_CASE("GIVEN a level WHEN written to the journal THEN its sd-daemon priority is syslog's", "[logging]") {
  CHECK(journalPriority(spdlog::level::trace) == 7);     // LOG_DEBUG
  CHECK(journalPriority(spdlog::level::debug) == 7);     // LOG_DEBUG
  CHECK(journalPriority(spdlog::level::info) == 6);      // LOG_INFO
  CHECK(journalPriority(spdlog::level::warn) == 4);      // LOG_WARNING
  CHECK(journalPriority(spdlog::level::err) == 3);       // LOG_ERR
  CHECK(journalPriority(spdlog::level::critical) == 2);  // LOG_CRIT
}

TEST_CASE("GIVEN JOURNAL_STREAM WHEN compared with a descriptor THEN only its own device:inode matches", "[logging]") {
  char path[] = "/tmp/toposlam-journal-XXXXXX";
  const int fd = mkstemp(path);
  REQUIRE(fd >= 0);
  struct stat st {};
  REQUIRE(fstat(fd, &st) == 0);
  const std::string own = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  const std::string other_inode = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino + 1);
  CHECK(isJournalStream(fd, own.c_str()));
  CHECK_FALSE(isJournalStream(fd, other_inode.c_str()));
  CHECK_FALSE(isJournalStream(fd, nullptr));
  CHECK_FALSE(isJournalStream(fd, ""));
  CHECK_FALSE(isJournalStream(fd, "journal"));
  CHECK_FALSE(isJournalStream(fd, (own + "x").c_str()));
  CHECK_FALSE(isJournalStream(-1, own.c_str()));
  close(fd);
  unlink(path);
}

TEST_CASE("GIVEN the two formats WHEN a line is formatted THEN the journal's has a priority and no time", "[logging]") {
  CHECK(formatted(true, spdlog::level::info, "toposlamd: running") == "<6>toposlamd: running\n");
  CHECK(formatted(true, spdlog::level::warn, "camera reconnecting") == "<4>camera reconnecting\n");
  CHECK(formatted(true, spdlog::level::err, "no map loads") == "<3>no map loads\n");
  CHECK(formatted(true, spdlog::level::debug, "step") == "<7>step\n");
  // On a terminal or a file: spdlog's default pattern, timestamped, without the logger's name.
  const std::string plain = formatted(false, spdlog::level::warn, "camera reconnecting");
  CHECK(plain.size() == std::string("[2026-12-02 08:10:09.119] [warning] camera reconnecting\n").size());
  CHECK(plain.rfind("[20", 0) == 0);
  CHECK(plain.find("] [warning] camera reconnecting\n") == 24);
  CHECK(plain.find("toposlamd") == std::string::npos);
}
