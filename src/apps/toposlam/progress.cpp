// The commands' progress line; see progress.hpp.
#include "progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace toposlam::cli {

namespace {

bool wanted(bool quiet) {
  if (quiet) return false;
  if (const char* force = std::getenv("TOPOSLAM_PROGRESS"); force != nullptr && *force != '\0')
    return std::strcmp(force, "0") != 0;
  return isatty(STDERR_FILENO) == 1;
}

std::string duration(double seconds) {
  char text[32];
  if (seconds < 60) std::snprintf(text, sizeof text, "%.0fs", std::ceil(seconds));
  else if (seconds < 3600) std::snprintf(text, sizeof text, "%dm%02ds", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  else std::snprintf(text, sizeof text, "%dh%02dm", static_cast<int>(seconds) / 3600, static_cast<int>(seconds) % 3600 / 60);
  return text;
}

}  // namespace

Progress::Progress(std::string command, std::string unit, std::int64_t total, bool quiet)
    : command_(std::move(command)), unit_(std::move(unit)), total_(total), enabled_(wanted(quiet)),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

Progress::~Progress() { finish(); }

double Progress::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string Progress::line(const std::string& command, const std::string& unit, std::int64_t done, std::int64_t total,
                           double seconds) {
  const double rate = seconds > 0 ? static_cast<double>(done) / seconds : 0.0;
  char text[192];
  if (total > 0) {
    const double left = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
    std::snprintf(text, sizeof text, "%s: %lld/%lld %s  %3.0f%%  %.1f %s/s  ETA %s", command.c_str(),
                  static_cast<long long>(done), static_cast<long long>(total), unit.c_str(),
                  100.0 * static_cast<double>(done) / static_cast<double>(total), rate, unit.c_str(),
                  rate > 0 ? duration(left).c_str() : "?");
  } else {
    std::snprintf(text, sizeof text, "%s: %lld %s  %.1f %s/s", command.c_str(), static_cast<long long>(done), unit.c_str(),
                  rate, unit.c_str());
  }
  return text;
}

std::string Progress::summary(const std::string& command, const std::string& unit, std::int64_t done, double seconds) {
  char text[160];
  std::snprintf(text, sizeof text, "%s: %lld %s in %.1f s (%.1f %s/s)", command.c_str(), static_cast<long long>(done),
                unit.c_str(), seconds, seconds > 0 ? static_cast<double>(done) / seconds : 0.0, unit.c_str());
  return text;
}

void Progress::update(std::int64_t done) {
  done_ = done;
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_draw_ < std::chrono::milliseconds(250) && done != total_) return;
  last_draw_ = now;
  std::fprintf(stderr, "\r%s\033[K", line(command_, unit_, done, total_, elapsed()).c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::clearLine() {
  if (!enabled_ || !drawn_) return;
  std::fputs("\r\033[K", stderr);
  drawn_ = false;
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  clearLine();
  std::fprintf(stderr, "%s\n", summary(command_, unit_, done_, elapsed()).c_str());
  std::fflush(stderr);
}

}  // namespace toposlam::cli
