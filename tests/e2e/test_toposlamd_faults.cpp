// End to end, the real toposlamd under the faults of issue 19, each in a few seconds with LCM on memq://
// (in process, no network): a damaged map with a good .prev, a second daemon on the same map, temporary
// files a kill -9 left, a map made with another keypoint backend, frames that claim 65500x65500 pixels,
// and the signals that used to kill it without a final save (SIGUSR1/2, SIGALRM, SIGPIPE).
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kSamples = std::string(TOPOSLAM_SAMPLES_DIR) + "/samples";

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

void nap() {
  timespec t{0, 20'000'000};  // polling a child or its log, not a synchronisation
  nanosleep(&t, nullptr);
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// toposlamd started with `args` (after the binary), stdout and stderr to `log`; with a file-size limit
/// (ulimit -f, bytes) when `file_size_limit` is not 0, and SIGXFSZ at its default as a shell leaves it.
pid_t startDaemon(const fs::path& log, const std::vector<std::string>& args, const fs::path& cwd = {},
                  rlim_t file_size_limit = 0) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (!cwd.empty() && chdir(cwd.c_str()) != 0) _exit(126);
    if (file_size_limit > 0) {
      const rlimit limit{file_size_limit, file_size_limit};
      if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(126);
      signal(SIGXFSZ, SIG_DFL);
    }
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    unsetenv("NOTIFY_SOCKET");
    std::vector<char*> argv;
    static std::string binary = TOPOSLAMD_BINARY;
    argv.push_back(binary.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(binary.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

/// Exit code once `pid` ended within `limit_s` (128 + signal if killed), else -1 (then it is killed).
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
    nap();
  }
}

/// True once `log` contains `text` (within `limit_s`).
bool waitForLog(const fs::path& log, const std::string& text, double limit_s) {
  const auto start = Clock::now();
  while (secondsSince(start) < limit_s) {
    if (readText(log).find(text) != std::string::npos) return true;
    nap();
  }
  return false;
}

/// Runs toposlamd to the end of a finite source; returns its exit code.
int runDaemon(const fs::path& log, const std::vector<std::string>& args, const fs::path& cwd = {}) {
  return waitForExit(startDaemon(log, args, cwd), 60.0);
}

fs::path freshDirectory(const std::string& name) {
  const fs::path dir = fs::path(TOPOSLAM_BINARY_DIR) / "e2e" / ("faults-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// A folder with the first `n` samples.
fs::path sampleFolder(const fs::path& dir, int n) {
  const fs::path frames = dir / "frames";
  fs::create_directories(frames);
  for (int i = 1; i <= n; ++i)
    fs::copy_file(kSamples + "/" + std::to_string(i) + ".jpg", frames / (std::to_string(i) + ".jpg"));
  return frames;
}

// --overflow block: a folder plays as fast as it is read, and with drop_oldest (the default before `auto`) a
// loaded machine dropped one of the 3 good frames ("2 frames published, 1 dropped"); `auto` picks block for a
// folder, spelled out so the counts here never depend on the default.
std::vector<std::string> daemonArgs(const fs::path& frames, const fs::path& map) {
  return {"--source", "images:" + frames.string(), "--map", map.string(), "--lcm-url", "memq://",
          "--overflow", "block"};
}

std::size_t countPrefix(const fs::path& dir, const std::string& prefix) {
  std::size_t n = 0;
  for (const auto& entry : fs::directory_iterator(dir)) n += entry.path().filename().string().rfind(prefix, 0) == 0;
  return n;
}

void flipMiddleByte(const fs::path& path) {
  std::string bytes = readText(path);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace

SCENARIO("GIVEN a damaged map.tsm and a good .prev WHEN toposlamd starts THEN it resumes .prev and keeps the damaged file") {
  const fs::path dir = freshDirectory("damaged");
  const fs::path frames = sampleFolder(dir, 6);
  const fs::path map = dir / "map.tsm";
  REQUIRE(runDaemon(dir / "run1.log", daemonArgs(frames, map)) == 0);
  REQUIRE(runDaemon(dir / "run2.log", daemonArgs(frames, map)) == 0);  // map.tsm.prev = run 1's map
  REQUIRE(fs::exists(dir / "map.tsm.prev"));
  const std::string good_prev = readText(dir / "map.tsm.prev");
  flipMiddleByte(map);

  const int code = runDaemon(dir / "run3.log", daemonArgs(frames, map));
  const std::string log = readText(dir / "run3.log");
  INFO(log);
  CHECK(code == 0);
  CHECK_THAT(log, Catch::Contains("checksum mismatch") && Catch::Contains("moved it to " + map.string() + ".damaged-") &&
                      Catch::Contains("resumed the map " + map.string() + ".prev"));
  CHECK_FALSE(Catch::Contains("starting a new map").match(log));
  CHECK(countPrefix(dir, "map.tsm.damaged-") == 1);
  CHECK(readText(dir / "map.tsm.prev") == good_prev);  // the last good map was not pushed out

  // It happens again (inline, not a WHEN section, so the daemon runs above are not repeated): the earlier
  // damaged file is kept beside the new one.
  flipMiddleByte(map);
  CHECK(runDaemon(dir / "run4.log", daemonArgs(frames, map)) == 0);
  CHECK(countPrefix(dir, "map.tsm.damaged-") == 2);
}

SCENARIO("GIVEN temporary files a kill -9 left and a frame claiming 65500x65500 WHEN toposlamd runs THEN the "
         "orphans go, the frame is skipped and named, and the run ends normally") {
  const fs::path dir = freshDirectory("orphans");
  const fs::path frames = sampleFolder(dir, 4);
  {
    std::string jpeg = readText(frames / "1.jpg");
    const std::size_t sof = jpeg.find("\xFF\xC0");
    REQUIRE(sof != std::string::npos);
    jpeg[sof + 5] = jpeg[sof + 7] = '\xFF';
    jpeg[sof + 6] = jpeg[sof + 8] = '\xDC';  // 65500 = 0xFFDC
    std::ofstream(frames / "3.jpg", std::ios::binary | std::ios::trunc) << jpeg;
  }
  const fs::path map = dir / "map.tsm";
  std::ofstream(dir / ".map.tsm.Ab12Cd") << "half a map";
  std::ofstream(dir / ".map.tsm.Zz99Yy.prev") << "x";
  const int code = runDaemon(dir / "run.log", daemonArgs(frames, map));
  const std::string log = readText(dir / "run.log");
  INFO(log);
  CHECK(code == 0);
  CHECK_THAT(log, Catch::Contains("removed 2 temporary file(s)") &&
                      Catch::Contains((frames / "3.jpg").string() + ": 65500x65500 pixels"));
  CHECK_THAT(log, Catch::Contains("3 frames published"));
  CHECK_FALSE(fs::exists(dir / ".map.tsm.Ab12Cd"));
  CHECK_FALSE(fs::exists(dir / ".map.tsm.Zz99Yy.prev"));
  CHECK(fs::exists(map));
}

SCENARIO(
    "GIVEN a folder of 4 good frames, 30 truncated files and 2 claiming 65500x65500 WHEN toposlamd plays it "
    "THEN the 32 are counted by reason, 5 are named in the log and one line sums up the other 27") {
  const fs::path dir = freshDirectory("bad-files");
  const fs::path frames = sampleFolder(dir, 4);
  const std::string jpeg = readText(frames / "1.jpg");
  for (int i = 0; i < 30; ++i)  // cut after 200 bytes: no end marker
    std::ofstream(frames / std::string("t").append(std::to_string(i)).append(".jpg"), std::ios::binary)
        << jpeg.substr(0, 200);
  std::string huge = jpeg;
  const std::size_t sof = huge.find("\xFF\xC0");
  REQUIRE(sof != std::string::npos);
  huge[sof + 5] = huge[sof + 7] = '\xFF';
  huge[sof + 6] = huge[sof + 8] = '\xDC';  // 65500 = 0xFFDC
  for (int i = 0; i < 2; ++i)
    std::ofstream(frames / std::string("h").append(std::to_string(i)).append(".jpg"), std::ios::binary)
        << huge;
  const int code = runDaemon(dir / "run.log", daemonArgs(frames, dir / "map.tsm"));
  const std::string log = readText(dir / "run.log");
  INFO(log);
  CHECK(code == 0);
  CHECK_THAT(log, Catch::Contains("4 frames published") &&
                      Catch::Contains("skipped 32 frames (truncated 30, too large 2)"));
  std::size_t named = 0, summaries = 0;
  for (std::size_t at = log.find("images: skipping "); at != std::string::npos;
       at = log.find("images: skipping ", at + 1))
    ++(log.compare(at, 36, "images: skipping bad files: 27 more ") == 0 ? summaries : named);
  CHECK(named == 5 + 1);  // the fifth line also says "(images: skipping bad files: further ones are ...)"
  CHECK(summaries == 1);
  CHECK_THAT(log, Catch::Contains("images: skipping bad files: 27 more suppressed (32 in all)"));
}

SCENARIO("GIVEN a map made with ORB keypoints WHEN toposlamd resumes it with SIFT THEN it refuses naming both") {
  const fs::path dir = freshDirectory("settings");
  const fs::path frames = sampleFolder(dir, 3);
  const fs::path map = dir / "map.tsm";
  REQUIRE(runDaemon(dir / "orb.log", daemonArgs(frames, map)) == 0);
  const std::string before = readText(map);
  std::ofstream(dir / "sift.yaml") << "fingerprint:\n  keypoints:\n    backend: sift\n";
  std::vector<std::string> args = daemonArgs(frames, map);
  args.insert(args.end(), {"--config", (dir / "sift.yaml").string()});
  const int code = runDaemon(dir / "sift.log", args);
  const std::string log = readText(dir / "sift.log");
  INFO(log);
  CHECK(code == 2);  // toposlamd's exit code for a start-up error
  CHECK_THAT(log, Catch::Contains(map.string()) && Catch::Contains("keypoints=orb") && Catch::Contains("keypoints=sift"));
  CHECK(readText(map) == before);  // nothing moved or overwritten
  CHECK(countPrefix(dir, "map.tsm.damaged") == 0);
}

SCENARIO("GIVEN a running toposlamd WHEN a second one starts on its map, and it gets SIGUSR1, SIGUSR2, SIGALRM and "
         "SIGPIPE THEN the second is refused naming the lock, and the first saves and exits 0 on SIGQUIT") {
  const fs::path dir = freshDirectory("lock");
  const fs::path map = dir / "map.tsm";
  const std::vector<std::string> args = {"--source", "sim:office?route=loop2&size=160x120&rate=10", "--map",
                                         map.string(), "--lcm-url", "memq://"};
  const pid_t first = startDaemon(dir / "first.log", args);
  REQUIRE(first > 0);
  const bool running = waitForLog(dir / "first.log", "toposlamd: running", 30.0);
  INFO(readText(dir / "first.log"));
  REQUIRE(running);

  const int second = runDaemon(dir / "second.log", args);
  const std::string second_log = readText(dir / "second.log");
  INFO(second_log);
  CHECK(second == 2);  // a start-up error
  CHECK_THAT(second_log, Catch::Contains("in use by another toposlam process (process " + std::to_string(first) + ")") &&
                             Catch::Contains(map.string() + ".lock"));

  for (int s : {SIGUSR1, SIGUSR2, SIGALRM}) {
    kill(first, s);
    CHECK(waitForLog(dir / "first.log", std::string(strsignal(s)) + " received: ignored", 10.0));
  }
  kill(first, SIGPIPE);
  kill(first, SIGQUIT);
  const int code = waitForExit(first, 30.0);
  const std::string log = readText(dir / "first.log");
  INFO(log);
  CHECK(code == 0);
  CHECK_THAT(log, Catch::Contains("received: finishing the filter step"));
  CHECK(fs::exists(map));
}

SCENARIO("GIVEN --map \"\" WHEN toposlamd runs THEN no map file is written (not even ./map.tsm)") {
  const fs::path dir = freshDirectory("no-map");
  const fs::path frames = sampleFolder(dir, 3);
  unsetenv("STATE_DIRECTORY");
  const int code = runDaemon(dir / "run.log", {"--source", "images:" + frames.string(), "--map", "", "--lcm-url", "memq://"}, dir);
  INFO(readText(dir / "run.log"));
  CHECK(code == 0);
  CHECK_FALSE(fs::exists(dir / "map.tsm"));
  CHECK(countPrefix(dir, "map.tsm") == 0);
}

SCENARIO("GIVEN toposlamd whose log pipe is closed (the reader gone) WHEN it runs THEN it is not killed by SIGPIPE "
         "and saves its map") {
  const fs::path dir = freshDirectory("closed-pipe");
  const fs::path frames = sampleFolder(dir, 3);
  const fs::path map = dir / "map.tsm";
  int pipe_fds[2];
  REQUIRE(pipe(pipe_fds) == 0);
  close(pipe_fds[0]);  // no reader: every log write fails with EPIPE (and raises SIGPIPE)
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(pipe_fds[1], 1);
    dup2(pipe_fds[1], 2);
    signal(SIGPIPE, SIG_DFL);  // as a shell would start it
    const std::string binary = TOPOSLAMD_BINARY;
    execl(binary.c_str(), binary.c_str(), "--source", ("images:" + frames.string()).c_str(), "--map", map.c_str(),
          "--lcm-url", "memq://", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(pipe_fds[1]);
  const int code = waitForExit(pid, 60.0);
  CHECK(code == 0);  // 141 = killed by SIGPIPE
  CHECK(fs::exists(map));
}

namespace {

/// The representative frame of each place in a map file toposlamd saved (its application data,
/// "toposlamd-frames F0 F1 ...", -1 for the places of an earlier run).
std::vector<long long> representativeFrames(const fs::path& map) {
  const std::string bytes = readText(map);
  const std::string key = "toposlamd-frames";
  const std::size_t at = bytes.find(key);
  if (at == std::string::npos || at < 8) return {};
  // The application data is bytes(x): its u64 size (little-endian), then x.
  std::uint64_t size = 0;
  for (std::size_t i = 0; i < 8; ++i) size |= std::uint64_t{static_cast<unsigned char>(bytes[at - 8 + i])} << (8 * i);
  std::istringstream in(bytes.substr(at + key.size(), size - key.size()));
  std::vector<long long> frames;
  long long f = 0;
  while (in >> f) frames.push_back(f);
  return frames;
}

/// The map's "source.last_frame" setting (the last frame of its source it holds), -1 when it records none.
long long lastMappedFrame(const fs::path& map) {
  const std::string bytes = readText(map);
  const std::string key = "source.last_frame=";  // a "key=value" line of the map's settings
  const std::size_t at = bytes.find(key);
  return at == std::string::npos ? -1 : std::stoll(bytes.substr(at + key.size()));
}

}  // namespace

SCENARIO("GIVEN toposlamd stopped part-way through an images: folder WHEN it restarts on the same folder THEN it "
         "continues after the last frame the map holds, so each frame is mapped once") {
  const fs::path dir = freshDirectory("restart-continues");
  constexpr int kFrames = 40;
  const fs::path frames = sampleFolder(dir, kFrames);
  const fs::path map = dir / "map.tsm";
  std::vector<std::string> paced = daemonArgs(frames, map);
  paced[1] += "?fps=1&rate=8";  // 1 Hz timestamps (the samples are keyframes), 8 Hz real time: SIGTERM part-way
  const pid_t first = startDaemon(dir / "run1.log", paced);
  REQUIRE(first > 0);
  REQUIRE(waitForLog(dir / "run1.log", "toposlamd: running", 30.0));
  // Until the map holds a place or two (each place message is logged at debug level only, so by time).
  const auto started = Clock::now();
  while (secondsSince(started) < 2.5) nap();
  kill(first, SIGTERM);
  REQUIRE(waitForExit(first, 30.0) == 0);
  const long long last1 = lastMappedFrame(map);
  const std::vector<long long> places1 = representativeFrames(map);
  INFO("run 1: " << places1.size() << " places, last frame " << last1 << "\n" << readText(dir / "run1.log"));
  REQUIRE(!places1.empty());
  REQUIRE(last1 >= 0);
  REQUIRE(last1 < kFrames - 1);
  for (long long f : places1) CHECK(f <= last1);

  // The restart reads only the frames after the last one mapped, says so, and maps them.
  REQUIRE(runDaemon(dir / "run2.log", daemonArgs(frames, map)) == 0);
  const std::string log2 = readText(dir / "run2.log");
  const std::vector<long long> places2 = representativeFrames(map);
  INFO(log2);
  const std::string last_name = std::to_string(last1 + 1) + ".jpg";  // sample k is frame k - 1
  CHECK_THAT(log2, Catch::Contains("continuing images:" + frames.string() + " after frame " + std::to_string(last1) +
                                   " (" + last_name + "), the last one the map holds: skipping the " +
                                   std::to_string(last1 + 1) + " frames already mapped"));
  CHECK_THAT(log2, Catch::Contains("toposlamd: " + std::to_string(kFrames - 1 - last1) + " frames published"));
  REQUIRE(places2.size() > places1.size());
  for (std::size_t i = 0; i < places1.size(); ++i) CHECK(places2[i] == -1);  // run 1's places, resumed
  for (std::size_t i = places1.size(); i < places2.size(); ++i) {
    CHECK(places2[i] > last1);
    CHECK(places2[i] < kFrames);
  }
  const long long last2 = lastMappedFrame(map);
  CHECK(last2 > last1);
  CHECK(last2 <= kFrames - 1);

  // Once every frame is mapped, a restart maps nothing and ends normally (Restart=on-failure stops there)...
  REQUIRE(runDaemon(dir / "run3.log", daemonArgs(frames, map)) == 0);
  const std::string log3 = readText(dir / "run3.log");
  INFO(log3);
  if (last2 == kFrames - 1) {
    CHECK_THAT(log3, Catch::Contains("the map holds every frame of images:" + frames.string()) &&
                         Catch::Contains("toposlamd: 0 frames published"));
    CHECK(representativeFrames(map).size() == places2.size());
  }
  CHECK(lastMappedFrame(map) == last2);  // and the map still says where the folder stands

  // ...and the explicit option reads the folder from its first frame again.
  std::vector<std::string> again = daemonArgs(frames, map);
  again.push_back("--source-from-start");
  REQUIRE(runDaemon(dir / "run4.log", again) == 0);
  const std::string log4 = readText(dir / "run4.log");
  INFO(log4);
  CHECK_THAT(log4, Catch::Contains("reading it from its first frame again (map.source_from_start)") &&
                       Catch::Contains("toposlamd: " + std::to_string(kFrames) + " frames published"));
  const std::vector<long long> places4 = representativeFrames(map);
  REQUIRE(places4.size() > places2.size());
  CHECK(places4[places2.size()] <= last1);  // the first new place is from the start of the folder
}

SCENARIO("GIVEN a map whose last frame is not in the folder any more WHEN toposlamd restarts THEN it says so and "
         "reads the folder from its first frame") {
  const fs::path dir = freshDirectory("restart-other-folder");
  const fs::path frames = sampleFolder(dir, 8);
  const fs::path map = dir / "map.tsm";
  REQUIRE(runDaemon(dir / "run1.log", daemonArgs(frames, map)) == 0);
  const long long last1 = lastMappedFrame(map);
  REQUIRE(last1 >= 0);
  const std::string last_name = std::to_string(last1 + 1) + ".jpg";
  for (int i = 1; i <= 8; ++i) {
    const std::string name = std::to_string(i) + ".jpg";
    fs::rename(frames / name, frames / std::string("b").append(name));
  }
  REQUIRE(runDaemon(dir / "run2.log", daemonArgs(frames, map)) == 0);
  const std::string log2 = readText(dir / "run2.log");
  INFO(log2);
  CHECK_THAT(log2, Catch::Contains("images: " + frames.string() + " has no file " + last_name) &&
                       Catch::Contains("starting from its first frame") &&
                       Catch::Contains("toposlamd: 8 frames published"));
}

// ---- a map known to be savable, every terminating signal, the settings a map records (issue 41) ---------

namespace {

/// A shell command's exit code (its output to `log`).
int runCommand(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " >" + log.string() + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

/// zlib's CRC-32 (the checksum of map format 3 and 4), bit by bit: the test has no zlib of its own.
std::uint32_t crc32Of(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char ch : bytes) {
    crc ^= static_cast<unsigned char>(ch);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xFFFFFFFFu;
}

std::uint64_t readLe(const std::string& bytes, std::size_t at, int size) {
  std::uint64_t value = 0;
  for (int i = 0; i < size; ++i) value |= std::uint64_t{static_cast<unsigned char>(bytes[at + i])} << (8 * i);
  return value;
}

void putLe(std::string& out, std::uint64_t value, int size) {
  for (int i = 0; i < size; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

/// The map file rewritten as format 3 wrote it: the same filter and application data, its settings only the
/// keypoints and the source (what maps recorded before every decision setting was).
std::string asFormat3(const std::string& map) {
  constexpr std::size_t kHeader = 32;
  std::size_t at = kHeader;
  std::string payload;
  for (int field = 0; field < 2; ++field) {  // bytes(filter state), bytes(application data)
    const std::size_t size = static_cast<std::size_t>(readLe(map, at, 8));
    payload += map.substr(at, 8 + size);
    at += 8 + size;
  }
  std::istringstream lines(map.substr(at + 8, static_cast<std::size_t>(readLe(map, at, 8))));
  std::string settings;
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("keypoints=", 0) == 0 || line.rfind("source=", 0) == 0) settings += line + "\n";
  putLe(payload, settings.size(), 8);
  payload += settings;
  std::string out = map.substr(0, 8);
  putLe(out, 3, 4);
  putLe(out, 0, 4);
  putLe(out, payload.size(), 8);
  putLe(out, crc32Of(payload), 8);
  return out + payload;
}

}  // namespace

SCENARIO("GIVEN a directory at the map path, or a folder where no file can be created WHEN toposlamd starts THEN "
         "it exits 2 at once naming the problem, before any frame") {
  const fs::path dir = freshDirectory("unsavable");
  const fs::path frames = sampleFolder(dir, 3);
  fs::path map;
  std::string problem;
  SECTION("a directory at the map path") {
    map = dir / "map.tsm";
    fs::create_directory(map);
    problem = map.string() + " is a directory";
  }
  SECTION("a folder where no file can be created") {
    // Root ignores permission bits; sysfs takes no new file, even from root.
    fs::path folder = "/sys";
    if (geteuid() != 0) {
      folder = dir / "read-only";
      fs::create_directory(folder);
      fs::permissions(folder, fs::perms::owner_read | fs::perms::owner_exec, fs::perm_options::replace);
    }
    map = folder / "map.tsm";
    problem = "cannot create a file in " + folder.string();
  }
  const auto started = Clock::now();
  const int code = runDaemon(dir / "run.log", daemonArgs(frames, map));
  const double seconds = secondsSince(started);
  const std::string log = readText(dir / "run.log");
  INFO(log);
  WARN("refused in " << seconds << " s");
  CHECK(code == 2);
  CHECK_THAT(log, Catch::Contains("toposlamd: error: the map " + map.string() + " could not be saved: " + problem));
  CHECK_FALSE(Catch::Contains("toposlamd: source").match(log));  // nothing opened, no frame read
  CHECK(seconds < 10.0);
  std::error_code ignored;
  fs::permissions(dir / "read-only", fs::perms::owner_all, fs::perm_options::replace, ignored);
}

SCENARIO("GIVEN a file-size limit smaller than the map WHEN toposlamd saves it THEN every save fails with EFBIG, "
         "is retried and reported, the process is not killed by SIGXFSZ, and the previous map is kept") {
  const fs::path dir = freshDirectory("file-size-limit");
  const fs::path frames = sampleFolder(dir, 12);
  const fs::path map = dir / "map.tsm";
  REQUIRE(runDaemon(dir / "run1.log", daemonArgs(frames, map)) == 0);
  const std::string before = readText(map);
  // Half the map: every save of it fails (a snapshot of the resumed map is a little smaller than the file).
  // The log file is limited too: it stays far below.
  const rlim_t limit = before.size() / 2;
  INFO("map " << before.size() << " bytes, limit " << limit);
  REQUIRE(before.size() > 20000);
  std::ofstream(dir / "periodic.yaml") << "map:\n  save_period_s: 1\n";
  std::vector<std::string> args = daemonArgs(frames, map);
  args[1] += "?rate=4";  // 12 frames in 3 s of real time: periodic saves on the way
  args.insert(args.end(), {"--source-from-start", "--config", (dir / "periodic.yaml").string()});
  const int code = waitForExit(startDaemon(dir / "run2.log", args, {}, limit), 60.0);
  const std::string log = readText(dir / "run2.log");
  INFO(log);
  CHECK(code == 1);  // the final save failed: an error, not death by SIGXFSZ (153)
  CHECK_THAT(log, Catch::Contains("periodic map save to " + map.string() + " failed (1 in a row; retried, the run goes on)") &&
                      Catch::Contains(std::strerror(EFBIG)) && Catch::Contains("trying the map save again in") &&
                      Catch::Contains("files are limited to " + std::to_string(limit) + " bytes here (ulimit -f)") &&
                      Catch::Contains("saving the map to " + map.string() + " failed 3 times"));
  CHECK(readText(map) == before);  // the previous map, whole
  CHECK(countPrefix(dir, ".map.tsm.") == 0);
}

SCENARIO("GIVEN a running toposlamd WHEN it gets any signal that would end it and can be caught THEN it saves the "
         "map and exits 0; SIGXFSZ is ignored") {
  const fs::path dir = freshDirectory("signals");
  const fs::path map = dir / "map.tsm";
  const std::vector<std::string> args = {"--source", "sim:office?route=loop2&size=160x120&rate=10", "--map",
                                         map.string(), "--lcm-url", "memq://"};
  for (const int s : {SIGXCPU, SIGPWR, SIGVTALRM, SIGPROF, SIGSYS, SIGIO, SIGSTKFLT, SIGRTMIN, SIGRTMIN + 5, SIGRTMAX}) {
    const fs::path log_path = dir / ("signal-" + std::to_string(s) + ".log");
    const pid_t pid = startDaemon(log_path, args);
    REQUIRE(pid > 0);
    REQUIRE(waitForLog(log_path, "toposlamd: running", 30.0));
    fs::remove(map);
    kill(pid, SIGXFSZ);  // ignored: its default would end the process at once (exit 153)
    kill(pid, s);
    const int code = waitForExit(pid, 30.0);
    const std::string log = readText(log_path);
    INFO("signal " << s << " (" << strsignal(s) << ")\n" << log);
    CHECK(code == 0);
    CHECK_THAT(log, Catch::Contains(std::string(strsignal(s)) + " received: finishing the filter step"));
    CHECK(fs::exists(map));
  }
}

SCENARIO("GIVEN a map made by `toposlam map --preset thesis` WHEN the default toposlamd resumes it THEN it is refused "
         "naming the settings that differ, unless map.resume_other_settings; a map of format 3 is resumed with a word") {
  const fs::path dir = freshDirectory("thesis-settings");
  const fs::path frames = sampleFolder(dir, 12);
  const std::string source = "images:" + frames.string();
  REQUIRE(runCommand(std::string(TOPOSLAM_CLI_BINARY) + " map --preset thesis --quiet " + source + " --out " +
                         (dir / "thesis").string(), dir / "map.log") == 0);
  const fs::path map = dir / "thesis" / "map.tsm";
  const std::string thesis_map = readText(map);
  std::vector<std::string> args = daemonArgs(frames, map);

  const int code = runDaemon(dir / "default.log", args);
  const std::string log = readText(dir / "default.log");
  {
    INFO(log);
    CHECK(code == 2);
    CHECK_THAT(log, Catch::Contains("toposlamd: error: the map " + map.string() + " was made with ") &&
                        Catch::Contains("segmentation.window=25") && Catch::Contains("topology.likelihood=absolute") &&
                        Catch::Contains("fingerprint.keypoints.orb_levels=") &&
                        Catch::Contains("but this run uses ") && Catch::Contains("segmentation.window=100") &&
                        Catch::Contains("--resume-other-settings continues it with this run's settings"));
    CHECK(readText(map) == thesis_map);  // nothing moved or overwritten
  }

  // Told to, it continues, naming what differs.
  args.push_back("--resume-other-settings");
  {
    const int resumed = runDaemon(dir / "other.log", args);
    const std::string other = readText(dir / "other.log");
    INFO(other);
    CHECK(resumed == 0);
    CHECK_THAT(other, Catch::Contains("was made with other settings; continuing it with this run's") &&
                          Catch::Contains("segmentation.window=25 (now 100)") && Catch::Contains("resumed the map"));
  }

  // A map of format 3 records the keypoints and the source only: it loads, with a word, and is continued.
  std::ofstream(map, std::ios::binary | std::ios::trunc) << asFormat3(thesis_map);
  args.pop_back();
  {
    const int old = runDaemon(dir / "format3.log", args);
    const std::string old_log = readText(dir / "format3.log");
    INFO(old_log);
    CHECK(old == 0);
    CHECK_THAT(old_log, Catch::Contains("records none of the") && Catch::Contains("made by an older toposlam") &&
                            Catch::Contains("resumed the map " + map.string()));
  }
}
