// End to end: the real toposlamd with a V4L2 camera that is not plugged in (a device node that does not
// exist), under a fake systemd notify socket with a 1 s watchdog and a 0.5 s heartbeat limit. The
// service must start (READY=1) instead of crash-looping, keep pinging the watchdog long after the
// heartbeat limit, say "camera reconnecting" in its STATUS=, and stop on SIGTERM with exit 0 and a saved
// map. LCM goes to memq:// (in process), so no network is needed.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../platform/systemd/fake_notify_socket.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// Exit code of `pid` once it ended within `limit_s` (128 + signal if killed), else -1 (then it is killed).
int waitForExit(pid_t pid, double limit_s) {
  const auto start = Clock::now();
  for (;;) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (secondsSince(start) > limit_s) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    timespec nap{0, 20'000'000};  // polling a child's exit, not a synchronisation
    nanosleep(&nap, nullptr);
  }
}

}  // namespace

SCENARIO("GIVEN toposlamd on a V4L2 camera that is not plugged in THEN it runs, pings the watchdog, says so, and stops cleanly") {
  const fs::path dir = fs::path(TOPOSLAM_BINARY_DIR) / "e2e" / "camera_absent";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path config = dir / "toposlam.yaml";
  std::ofstream(config) << "watchdog:\n  enabled: true\n  heartbeat_timeout_s: 0.5\n";
  const fs::path map = dir / "map.tsm";
  toposlam::test::FakeNotifySocket notify("camera-absent");

  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const int log = open((dir / "toposlamd.log").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(log, 1);
    dup2(log, 2);
    setenv("NOTIFY_SOCKET", notify.path().c_str(), 1);
    setenv("WATCHDOG_USEC", "1000000", 1);
    unsetenv("WATCHDOG_PID");
    const std::string binary = TOPOSLAMD_BINARY;
    execl(binary.c_str(), binary.c_str(), "--config", config.c_str(), "--source",
          "v4l2:/dev/toposlam-no-such-video77?size=320x240", "--map", map.c_str(), "--no-map-load", "--lcm-url",
          "memq://", static_cast<char*>(nullptr));
    _exit(127);
  }

  // Listen until a watchdog ping came more than 2.5 s (5x the heartbeat limit) after READY=1.
  const auto start = Clock::now();
  double ready_at = -1.0, last_ping_at = -1.0;
  int pings_after_limit = 0;
  std::string reconnecting_status;
  while (secondsSince(start) < 60.0 && !(ready_at >= 0 && last_ping_at - ready_at > 2.5 && !reconnecting_status.empty())) {
    const std::string message = notify.receive();
    if (message.empty()) break;  // 5 s of silence: the daemon died or hangs
    const double t = secondsSince(start);
    if (message == "READY=1") ready_at = t;
    if (message == "WATCHDOG=1") {
      last_ping_at = t;
      if (ready_at >= 0 && t - ready_at > 0.5) ++pings_after_limit;
    }
    if (message.rfind("STATUS=", 0) == 0 && message.find("camera reconnecting") != std::string::npos)
      reconnecting_status = message;
  }
  kill(pid, SIGTERM);
  const auto stop_sent = Clock::now();
  const int code = waitForExit(pid, 25.0);
  const double stop_s = secondsSince(stop_sent);
  std::ifstream log_file(dir / "toposlamd.log");
  std::stringstream log;
  log << log_file.rdbuf();
  INFO("toposlamd log:\n" << log.str());

  THEN("READY=1 came, the watchdog was fed for > 2.5 s past the limit, and STATUS= says reconnecting") {
    CHECK(ready_at >= 0.0);
    CHECK(last_ping_at - ready_at > 2.5);
    CHECK(pings_after_limit >= 4);  // twice per 1 s watchdog period
    CHECK_THAT(reconnecting_status, Catch::StartsWith("STATUS=running: ") && Catch::Contains("camera reconnecting (attempt"));
  }
  THEN("SIGTERM ends it with exit code 0 within the unit's stop timeout, and the map was saved") {
    CHECK(code == 0);
    CHECK(stop_s < 20.0);  // a hang guard (TimeoutStopSec is 30 s), not a speed measurement
    CHECK(fs::exists(map));
  }
}
