// The end-to-end tests' shared harness; see the header.
#include "e2e_harness.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

namespace toposlam::e2e {

ChildProcess::ChildProcess(const std::string& binary, const std::vector<std::string>& args,
                           const Options& options) {
  int fds[2] = {-1, -1};
  if (options.log_file.empty() && pipe2(fds, O_CLOEXEC) != 0)
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid_ == 0) {
    const int out = options.log_file.empty()
                        ? fds[1]
                        : open(options.log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0) _exit(126);
    dup2(out, 1);  // dup2 clears O_CLOEXEC on the copies
    dup2(out, 2);
    for (const auto& [name, value] : options.environment) setenv(name.c_str(), value.c_str(), 1);
    if (!options.pid_variable.empty())
      setenv(options.pid_variable.c_str(), std::to_string(getpid()).c_str(), 1);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(binary.c_str()));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(binary.c_str(), argv.data());
    _exit(127);
  }
  if (options.log_file.empty()) {
    close(fds[1]);
    output_fd_ = fds[0];
  }
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !exited_) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  if (output_fd_ >= 0) close(output_fd_);
}

void ChildProcess::readAvailable(int timeout_ms) {
  if (output_fd_ < 0) return;
  pollfd p{output_fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return;
  char buffer[4096];
  const ssize_t n = read(output_fd_, buffer, sizeof buffer);
  if (n > 0) {
    output_.append(buffer, static_cast<std::size_t>(n));
  } else if (n == 0 || errno != EINTR) {  // end of file: the child (and anything it started) closed it
    close(output_fd_);
    output_fd_ = -1;
  }
}

bool ChildProcess::waitForOutput(const std::string& text, int timeout_ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (output_.find(text) == std::string::npos) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
    if (left.count() <= 0 || output_fd_ < 0) return false;
    readAvailable(static_cast<int>(left.count()));
  }
  return true;
}

const std::string& ChildProcess::output() {
  for (std::size_t before = output_.size() + 1; output_fd_ >= 0 && output_.size() != before;) {
    before = output_.size();
    readAvailable(0);
  }
  return output_;
}

void ChildProcess::terminate() {
  if (!exited_) kill(pid_, SIGTERM);
}

int ChildProcess::poll() {
  if (exited_) return status_;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) == pid_) {
    exited_ = true;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  return exited_ ? status_ : -1;
}

int ChildProcess::stop() {
  if (!exited_) {
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    exited_ = true;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(2);  // the rest, up to end of file
  while (output_fd_ >= 0 && std::chrono::steady_clock::now() < end) readAvailable(100);
  return status_;
}

std::filesystem::path freshDirectory(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(TOPOSLAM_BINARY_DIR) / "e2e" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

namespace {

void onProbe(const lcm::ReceiveBuffer*, const std::string&, bool* heard) { *heard = true; }

}  // namespace

void skipUnlessMulticastLoopsBack(const std::string& url) {
  std::unique_ptr<lcm::LCM> l;
  try {
    l = openLcm(url);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skipped: %s\n", e.what());
    std::_Exit(77);
  }
  bool heard = false;
  const std::string channel = "TOPOSLAM_E2E_PROBE";
  l->subscribeFunction(channel, &onProbe, &heard);
  const std::uint8_t probe = 1;
  l->publish(channel, &probe, 1);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (!heard && std::chrono::steady_clock::now() < end) l->handleTimeout(100);
  if (!heard) {
    std::fprintf(stderr, "skipped: LCM multicast on %s does not loop back here\n", url.c_str());
    std::_Exit(77);
  }
}

std::unique_ptr<LcmSubscriber> subscribe(const std::string& url, Heard& heard) {
  const LcmChannels channels;
  return std::make_unique<LcmSubscriber>(
      url, channels,
      std::vector<std::string>{channels.place, channels.place_event, channels.status, channels.topology,
                               channels.motion},
      [&heard](const ReceivedMessage& m) {
        if (m.kind == "place") heard.places.push_back(m);
        if (m.kind == "place_event") heard.events.push_back(m);
        if (m.kind == "status") heard.statuses.push_back(m);
        if (m.kind == "topology") heard.topologies.push_back(m);
        if (m.kind == "motion") heard.motions.push_back(m);
      });
}

std::int64_t integerField(const ReceivedMessage& m, const std::string& name) {
  const std::string key = "\"" + name + "\":";
  const std::size_t at = m.json.find(key);
  return at == std::string::npos ? -1 : std::stoll(m.json.substr(at + key.size()));
}

double numberField(const ReceivedMessage& m, const std::string& name) {
  const std::string key = "\"" + name + "\":";
  const std::size_t at = m.json.find(key);
  return at == std::string::npos ? std::nan("") : std::stod(m.json.substr(at + key.size()));
}

double capturedAtUs(const ReceivedMessage& place) {
  return numberField(place, "publish_utime") - 1000.0 * numberField(place, "latency_ms");
}

std::int64_t framesCapturedIn(const std::vector<ReceivedMessage>& places, double from_us, double to_us) {
  std::int64_t n = 0;
  for (const ReceivedMessage& p : places) {
    const double t = capturedAtUs(p);
    n += t >= from_us && t < to_us ? 1 : 0;
  }
  return n;
}

MotionStatusHistory motionStatusHistory(const std::vector<ReceivedMessage>& statuses) {
  MotionStatusHistory h;
  for (std::size_t i = 0; i < statuses.size(); ++i) {
    const std::string& json = statuses[i].json;
    if (i == 0) h.first_says_none = json.find("\"motion_state\":\"none\"") != std::string::npos;
    if (h.first_used < 0 && json.find("\"motion_state\":\"used\"") != std::string::npos)
      h.first_used = static_cast<int>(i);
    if (h.first_lost < 0 && json.find("\"motion_state\":\"lost\"") != std::string::npos)
      h.first_lost = static_cast<int>(i);
    h.standing_frames = std::max(h.standing_frames, integerField(statuses[i], "motion_standing_frames"));
    if (json.find("\"motion_refused\"") != std::string::npos)
      h.refused = std::max(h.refused, integerField(statuses[i], "motion_refused"));
    if (json.find("\"motion_malformed\"") != std::string::npos)
      h.malformed = std::max(h.malformed, integerField(statuses[i], "motion_malformed"));
    if (json.find("\"motion_fragments_abandoned\"") != std::string::npos)
      h.fragments_abandoned = std::max(h.fragments_abandoned, integerField(statuses[i], "motion_fragments_abandoned"));
  }
  if (!statuses.empty()) h.messages = integerField(statuses.back(), "motion_messages");
  return h;
}

}  // namespace toposlam::e2e
