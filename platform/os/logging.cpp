// Logging set-up: stderr, --log-level, the journal's format; see the header.
#include "toposlam/platform/logging.hpp"

#include <sys/stat.h>

#include <cstdlib>
#include <cstdio>

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

namespace toposlam {

namespace {

/// The "%*" flag: "<N>" for the message's level (sd-daemon(3) prefixes, read by journald on its stream).
class JournalPriorityFlag final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& message, const std::tm&, spdlog::memory_buf_t& out) override {
    const char prefix[] = {'<', static_cast<char>('0' + journalPriority(message.level)), '>'};
    out.append(prefix, prefix + sizeof prefix);
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<JournalPriorityFlag>(); }
};

}  // namespace

std::optional<spdlog::level::level_enum> parseLogLevel(std::string_view name) {
  if (name == "trace") return spdlog::level::trace;
  if (name == "debug") return spdlog::level::debug;
  if (name == "info") return spdlog::level::info;
  if (name == "warn") return spdlog::level::warn;
  if (name == "error") return spdlog::level::err;
  return std::nullopt;
}

int journalPriority(spdlog::level::level_enum level) {
  switch (level) {
    case spdlog::level::trace:
    case spdlog::level::debug: return 7;
    case spdlog::level::info: return 6;
    case spdlog::level::warn: return 4;
    case spdlog::level::err: return 3;
    case spdlog::level::critical: return 2;
    default: return 6;
  }
}

bool isJournalStream(int fd, const char* journal_stream) {
  if (journal_stream == nullptr || journal_stream[0] == '\0') return false;
  unsigned long long device = 0, inode = 0;
  char rest = 0;
  if (std::sscanf(journal_stream, "%llu:%llu%c", &device, &inode, &rest) != 2) return false;
  struct stat st {};
  if (fstat(fd, &st) != 0) return false;
  return static_cast<unsigned long long>(st.st_dev) == device && static_cast<unsigned long long>(st.st_ino) == inode;
}

std::unique_ptr<spdlog::formatter> makeLogFormatter(bool journal) {
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  if (journal) {
    formatter->add_flag<JournalPriorityFlag>('*').set_pattern("%*%v");
  } else {
    formatter->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] %v");  // spdlog's default, without the logger's name
  }
  return formatter;
}

bool configureLogging(const std::string& program, spdlog::level::level_enum level) {
  const bool journal = isJournalStream(2, std::getenv("JOURNAL_STREAM"));
  spdlog::sink_ptr sink;
  if (journal)
    sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
  else
    sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();  // colours only on a terminal
  auto logger = std::make_shared<spdlog::logger>(program, std::move(sink));
  logger->set_formatter(makeLogFormatter(journal));
  logger->set_level(level);
  spdlog::set_default_logger(std::move(logger));
  return journal;
}

}  // namespace toposlam
