// `toposlam-bench startup`: how long a command takes from exec to exit and how much memory it touches,
// whole process (loading the shared libraries included): `toposlam --version`, `toposlam --help`, and
// `toposlam map` over the bundled frames (ms per frame). Each run is a child process started with
// posix_spawn; its time is the wall time to its exit, its memory the peak resident set (ru_maxrss) the
// kernel reports for it. Medians of --runs runs. Prints numbers, asserts nothing (docs/performance.md).
// The program measured is toposlam, not this one (the benchmarks were inside it until issue 15): --toposlam
// PATH, else the toposlam beside this program (both installed in /usr/bin), else the build tree's.
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "image_input.hpp"
#include "toposlam/io/file_sources.hpp"

extern char** environ;

namespace toposlam::cli {

namespace {

struct StartupBenchOptions {
  std::string toposlam;
  int runs = 9;
  std::string samples;
  bool json = false;
};

struct ChildRun {
  double ms = 0;
  double peak_mb = 0;
};

/// The toposlam to measure when no --toposlam is given: the one beside this program, else the build tree's.
std::string defaultToposlam() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::filesystem::path beside = self.parent_path() / "toposlam";
  if (!error && ::access(beside.c_str(), X_OK) == 0) return beside.string();
  return TOPOSLAM_BUILD_TREE_TOPOSLAM;
}

/// Runs `self` (toposlam) with `args` (stdout and stderr to /dev/null); throws when it cannot be started or
/// fails.
ChildRun runToposlam(const std::string& self, const std::vector<std::string>& args) {
  std::vector<char*> argv{const_cast<char*>(self.c_str())};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&files, 2, "/dev/null", O_WRONLY, 0);
  Stopwatch watch;
  pid_t pid = 0;
  const int error = posix_spawn(&pid, self.c_str(), &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  if (error != 0) throw std::runtime_error("bench startup: cannot start " + self);
  int status = 0;
  rusage usage{};
  while (wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) throw std::runtime_error("bench startup: wait4 failed");
  }
  const double ms = watch.elapsedMs();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("bench startup: '" + self + " " + args.front() + "' failed");
  return {ms, static_cast<double>(usage.ru_maxrss) / 1024.0};
}

void runStartupBench(const StartupBenchOptions& o) {
  BenchRows rows("startup", o.json);
  const std::size_t frames = listImageFiles(o.samples).size();
  const std::filesystem::path out = std::filesystem::temp_directory_path() / ("toposlam-bench-startup-" + std::to_string(::getpid()));
  struct Case {
    std::string name;
    std::vector<std::string> args;
    std::size_t per = 0;  // frames, for ms per frame
  };
  const std::vector<Case> cases = {
      {"--version", {"--version"}, 0},
      {"--help", {"--help"}, 0},
      {"map", {"map", "images:" + o.samples, "--out", out.string()}, frames},
  };
  rows.text() << "whole process, exec to exit; median of " << o.runs << " runs\n"
              << std::left << std::setw(12) << "command" << std::right << std::setw(12) << "median ms"
              << std::setw(10) << "min ms" << std::setw(14) << "ms/frame" << std::setw(12) << "peak MB" << "\n";
  for (const Case& c : cases) {
    std::vector<double> ms;
    double peak_mb = 0;
    for (int r = 0; r < o.runs; ++r) {
      const ChildRun run = runToposlam(o.toposlam, c.args);
      ms.push_back(run.ms);
      peak_mb = std::max(peak_mb, run.peak_mb);
    }
    const TimingSummary s = summarize(ms);
    const double min_ms = *std::min_element(ms.begin(), ms.end());
    const double per_frame = c.per ? s.median_ms / static_cast<double>(c.per) : 0.0;
    rows.row({{"command", c.name}, {"median_ms", s.median_ms}, {"min_ms", min_ms}, {"frames", static_cast<std::int64_t>(c.per)},
              {"ms_per_frame", per_frame}, {"peak_rss_mb", peak_mb}});
    rows.text() << std::left << std::setw(12) << c.name << std::right << std::fixed << std::setprecision(1)
                << std::setw(12) << s.median_ms << std::setw(10) << min_ms << std::setw(14) << std::setprecision(2)
                << per_frame << std::setw(12) << std::setprecision(1) << peak_mb << "\n";
  }
  std::error_code ignored;
  std::filesystem::remove_all(out, ignored);
}

}  // namespace

void addBenchStartup(CLI::App& bench) {
  auto options = std::make_shared<StartupBenchOptions>();
  options->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand(
      "startup", "Whole-process ms and peak MB of `toposlam --version`, `--help` and `map` over the sample frames");
  cmd->add_option("--toposlam", options->toposlam,
                  "The toposlam program to measure (default: the one beside this program, else the build "
                  "tree's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--runs", options->runs, "Runs of each command (the median is printed)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Folder of frames for `map`")->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the rows as one JSON object (the table goes to stderr)");
  cmd->callback([options] {
    if (options->toposlam.empty()) options->toposlam = defaultToposlam();
    runStartupBench(*options);
  });
}

}  // namespace toposlam::cli
