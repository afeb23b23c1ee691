// ThreadTable and ThreadSettings: names applied, failures to pin reported but not fatal, validation.
#include <catch2/catch.hpp>

#include <pthread.h>

#include <atomic>
#include <string>

#include "toposlam/pipeline/thread_table.hpp"

using namespace toposlam;

SCENARIO("Threads of the table carry their configured names") {
  GIVEN("a table with two named threads") {
    std::string seen_a, seen_b;
    {
      ThreadTable table;
      auto nameOf = [](std::string& out) {
        char name[16] = {};
        pthread_getname_np(pthread_self(), name, sizeof name);
        out = name;
      };
      table.start(ThreadSettings{"tsl-test-a"}, [&] { nameOf(seen_a); });
      table.start(ThreadSettings{"tsl-test-b"}, [&] { nameOf(seen_b); });
      CHECK(table.size() == 2);
      table.joinAll();
      table.joinAll();  // idempotent
      THEN("each thread saw its own name and no problem was recorded") {
        CHECK(seen_a == "tsl-test-a");
        CHECK(seen_b == "tsl-test-b");
        CHECK(table.warnings().empty());
      }
    }
  }
}

SCENARIO("A pinning that cannot be applied is reported, and the thread still runs") {
  GIVEN("a thread pinned to CPU 1023, which this machine does not have") {
    ThreadSettings settings{"tsl-test-pin"};
    settings.cpu = 1023;
    std::atomic<bool> ran{false};
    ThreadTable table;
    table.start(settings, [&] { ran = true; });
    table.joinAll();
    THEN("the body ran and the problem names the CPU") {
      CHECK(ran.load());
      REQUIRE(table.warnings().size() == 1);
      CHECK_THAT(table.warnings()[0], Catch::Contains("cannot pin to CPU 1023"));
    }
  }
}

SCENARIO("An exception escaping a thread body is recorded, not fatal") {
  ThreadTable table;
  table.start(ThreadSettings{"tsl-test-exc"}, [] { throw std::runtime_error("boom"); });
  table.joinAll();
  REQUIRE(table.warnings().size() == 1);
  CHECK_THAT(table.warnings()[0], Catch::Contains("boom"));
}

SCENARIO("Thread settings are validated with the key and its allowed range") {
  ThreadSettings s{"ok"};
  CHECK(s.validate().empty());
  s.name = "a-name-longer-than-15";
  CHECK_THAT(s.validate(), Catch::StartsWith("name:") && Catch::Contains("1 to 15"));
  s = ThreadSettings{"ok"};
  s.cpu = -2;
  CHECK_THAT(s.validate(), Catch::StartsWith("cpu:") && Catch::Contains("-1 (no pinning) .. 1023"));
  s = ThreadSettings{"ok"};
  s.policy = SchedulingPolicy::Fifo;
  CHECK_THAT(s.validate(), Catch::StartsWith("priority:") && Catch::Contains("1 .. 99"));
  s.priority = 10;
  CHECK(s.validate().empty());
  s = ThreadSettings{"ok"};
  s.nice = 20;
  CHECK_THAT(s.validate(), Catch::StartsWith("nice:") && Catch::Contains("-20 .. 19"));
}
