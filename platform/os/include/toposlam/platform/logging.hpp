// Logging set-up of toposlam, toposlamd and toposlam-bridge: one logger on stderr (stdout carries a
// command's results), the level from --log-level, and, when stderr is systemd's journal stream, lines in
// the journal's own format: an sd-daemon(3) "<N>" priority prefix and no timestamp (the journal adds its
// own), so `journalctl -p warning` and the colours of `journalctl` work.
//
// systemd sets JOURNAL_STREAM=<device>:<inode> of the stream it connects stdout/stderr to; stderr is the
// journal when its fstat() matches (a child that inherited the variable but writes elsewhere is not).
//
// Thread-safety: call configureLogging() once, at start, before any thread logs.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <spdlog/common.h>
#include <spdlog/formatter.h>

namespace toposlam {

/// The names --log-level accepts, from the most verbose: "trace|debug|info|warn|error".
inline constexpr const char* kLogLevelNames = "trace|debug|info|warn|error";

/// The spdlog level of a --log-level name, nullopt for anything else.
std::optional<spdlog::level::level_enum> parseLogLevel(std::string_view name);

/// The sd-daemon(3) priority of a level: trace and debug 7 (LOG_DEBUG), info 6, warn 4, error 3,
/// critical 2.
int journalPriority(spdlog::level::level_enum level);

/// True when file descriptor `fd` is the stream named by `journal_stream` ("<st_dev>:<st_ino>", decimal, as
/// systemd writes $JOURNAL_STREAM); false for an empty or malformed value.
bool isJournalStream(int fd, const char* journal_stream);

/// The line format: with `journal`, "<N>" + the message (no time, no level name: the priority says it);
/// otherwise "[time] [level] message" (spdlog's default without the logger name).
std::unique_ptr<spdlog::formatter> makeLogFormatter(bool journal);

/// Makes the default logger write to stderr at `level`, in the journal's format when stderr is
/// $JOURNAL_STREAM. Returns whether it did (for a start-up line that says where logs go).
bool configureLogging(const std::string& program, spdlog::level::level_enum level);

}  // namespace toposlam
