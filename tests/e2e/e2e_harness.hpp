// What the end-to-end tests share (label e2e; tests/e2e and tests/firmware-host): the programs under test
// as child processes (toposlamd, toposlam-bridge), the check that skips a test (exit 77) where LCM
// multicast cannot hear itself, and toposlamd's LCM messages as the tests read them. The tests run inside
// in_netns.sh's private network namespace, so their multicast stays there.
//
// Not thread-safe: one test thread uses these.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/platform/lcm_transport.hpp"

namespace toposlam::e2e {

/// A program under test as a child process (fork + exec, no shell). Its stdout and stderr go to
/// `log_file` when one is given, else into a pipe that this side reads (waitForOutput(), output()); a
/// test using the pipe must read it now and then (the child blocks once 64 KiB wait unread). The
/// destructor kills (SIGKILL) and reaps a child that is still running.
class ChildProcess {
 public:
  struct Options {
    std::filesystem::path log_file;                                ///< empty: a pipe read here
    std::vector<std::pair<std::string, std::string>> environment;  ///< variables set in the child
    std::string pid_variable;  ///< set to the child's own pid (as systemd sets WATCHDOG_PID); empty: none
  };
  /// Throws std::runtime_error when the pipe or the fork fails (exec failing shows as exit code 127).
  ChildProcess(const std::string& binary, const std::vector<std::string>& args, const Options& options);
  ChildProcess(const std::string& binary, const std::vector<std::string>& args)
      : ChildProcess(binary, args, Options{}) {}
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// Reads the pipe until `text` has appeared in the output or `timeout_ms` passed; true when it has.
  bool waitForOutput(const std::string& text, int timeout_ms);
  /// The output read from the pipe so far, after reading what is there now (does not wait).
  const std::string& output();
  /// Sends SIGTERM; returns at once.
  void terminate();
  /// The exit code once the child has ended (128 + signal when a signal ended it), else -1. Never blocks.
  int poll();
  /// SIGTERM, waits for the child, reads the rest of the pipe; returns the exit code as poll() does.
  int stop();
  pid_t pid() const { return pid_; }

 private:
  void readAvailable(int timeout_ms);

  pid_t pid_ = -1;
  int output_fd_ = -1;  ///< read end of the pipe, -1 with a log file or once the child closed it
  bool exited_ = false;
  int status_ = -1;
  std::string output_;
};

/// An empty folder `name` under the build tree's e2e/ (removed first if it exists).
std::filesystem::path freshDirectory(const std::string& name);

/// Exits the test program with 77 (ctest's SKIP_RETURN_CODE) unless LCM on `url` opens and hears its own
/// multicast within 1 s: the host has neither network namespaces (in_netns.sh) nor a multicast route.
void skipUnlessMulticastLoopsBack(const std::string& url);

/// What a test heard of toposlamd over LCM, by kind, in arrival order.
struct Heard {
  std::vector<ReceivedMessage> places, events, statuses, topologies;
  std::vector<ReceivedMessage> motions;  ///< TOPOSLAM_MOTION, whoever published it
};

/// Subscribes `heard` to toposlamd's output channels and to TOPOSLAM_MOTION (default channel names).
std::unique_ptr<LcmSubscriber> subscribe(const std::string& url, Heard& heard);

/// Handles LCM until `daemon` exits (or `deadline_s` passed: returns -2), calling `each` after every
/// batch (at least every 50 ms); returns the daemon's exit code. The datagrams of its last moments are
/// handled too.
template <typename Each>
int listenUntilExit(LcmSubscriber& subscriber, ChildProcess& daemon, double deadline_s, Each each) {
  const auto start = std::chrono::steady_clock::now();
  int code = -1;
  while ((code = daemon.poll()) < 0) {
    subscriber.handle(50);
    each();
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > deadline_s)
      return -2;
  }
  for (int i = 0; i < 5; ++i) subscriber.handle(20);  // late datagrams
  return code;
}

/// An integer field of a message's JSON, -1 when absent.
std::int64_t integerField(const ReceivedMessage& m, const std::string& name);
/// A number field of a message's JSON, NaN when absent.
double numberField(const ReceivedMessage& m, const std::string& name);

/// When the frame of a place message left its source (the clock motion is looked up at), microseconds of
/// CLOCK_MONOTONIC: the message's publish_utime minus its latency.
double capturedAtUs(const ReceivedMessage& place);
/// How many of `places` have a frame captured in [from_us, to_us).
std::int64_t framesCapturedIn(const std::vector<ReceivedMessage>& places, double from_us, double to_us);

/// The motion fields of toposlamd's status messages, in order: where motion_state first said used and
/// lost, the most standing frames reported and the motion messages of the last status.
struct MotionStatusHistory {
  bool first_says_none = false;      ///< the first status says "none"
  int first_used = -1;               ///< index of the first status saying "used", -1: none did
  int first_lost = -1;               ///< index of the first status saying "lost", -1: none did
  std::int64_t standing_frames = 0;  ///< largest motion_standing_frames
  std::int64_t messages = -1;        ///< motion_messages of the last status, -1 without a status
  std::int64_t refused = 0;          ///< largest motion_refused
  std::int64_t malformed = 0;        ///< largest motion_malformed
  std::int64_t fragments_abandoned = 0;  ///< largest motion_fragments_abandoned
};
MotionStatusHistory motionStatusHistory(const std::vector<ReceivedMessage>& statuses);

}  // namespace toposlam::e2e
