// Helper programs and per-thread settings (platform/os): exit statuses passed through, a missing program
// and a killed one told apart from success, PATH look-up, arguments passed without a shell; the thread
// name set, an absent CPU refused with an error number, CPU clocks that only move forward.
#include <catch2/catch.hpp>

#include <pthread.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "toposlam/platform/programs.hpp"
#include "toposlam/platform/thread_os.hpp"

using namespace toposlam;

SCENARIO("GIVEN helper programs WHEN run THEN their exit status comes back, failures are not success") {
  CHECK(programOnPath("sh"));
  CHECK_FALSE(programOnPath("toposlam-no-such-program"));
  CHECK_FALSE(programOnPath(""));
  CHECK(runProgram({"sh", "-c", "exit 0"}) == 0);
  CHECK(runProgram({"sh", "-c", "exit 3"}) == 3);
  CHECK(runProgram({"toposlam-no-such-program", "-x"}) != 0);
  CHECK(runProgram({"sh", "-c", "kill -9 $$"}) == -1);
  CHECK(runProgram({}) == -1);
}

SCENARIO("GIVEN an argument with spaces and quotes WHEN passed to a program THEN it arrives as one word") {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("toposlam-programs-" + std::to_string(::getpid()) + ".txt");
  const std::string word = "it's a \"word\" with $HOME";
  REQUIRE(runProgram({"sh", "-c", "printf '%s|%s' \"$1\" \"$#\" > \"$2\"", "sh", word, out.string()}) == 0);
  std::ifstream in(out);
  std::string text;
  std::getline(in, text);
  CHECK(text == word + "|2");
  std::filesystem::remove(out);
}

SCENARIO("GIVEN the calling thread WHEN its name and CPU are set THEN they hold or the error number says why") {
  std::thread([] {
    CHECK(setCurrentThreadName("tsl-test-thread-long-name") == 0);  // kept to 15 characters
    char name[32] = {};
    REQUIRE(pthread_getname_np(pthread_self(), name, sizeof name) == 0);
    CHECK(std::string(name) == "tsl-test-thread");
    CHECK(pinCurrentThread(1023) == EINVAL);  // no machine of ours has CPU 1023
    CHECK(setCurrentThreadNice(0) == 0);
  }).join();
}

SCENARIO("GIVEN namedWorkers as a pool's start hook WHEN a worker starts THEN it is named prefix-index") {
  std::string name;
  std::thread([&] {
    namedWorkers("tsl-vpack")(2);
    char buffer[32] = {};
    REQUIRE(pthread_getname_np(pthread_self(), buffer, sizeof buffer) == 0);
    name = buffer;
  }).join();
  CHECK(name == "tsl-vpack-2");
}

SCENARIO("GIVEN work done WHEN the CPU clocks are read THEN they move forward") {
  const double thread_before = threadCpuSeconds();
  const double process_before = processCpuSeconds();
  volatile double sink = 0;
  for (int i = 0; i < 2000000; ++i) sink = sink + i * 1e-9;
  CHECK(threadCpuSeconds() > thread_before);
  CHECK(processCpuSeconds() > process_before);
}
