// BoundedQueue: drop-oldest with exact counts, lossless pushWait, close() as end of stream.
#include <catch2/catch.hpp>

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "toposlam/pipeline/bounded_queue.hpp"

using toposlam::BoundedQueue;
using toposlam::QueueWait;

SCENARIO("A full queue drops its oldest item and counts it") {
  GIVEN("a queue of capacity 3") {
    BoundedQueue<int> queue(3);
    WHEN("10 items are pushed and none popped") {
      for (int i = 0; i < 10; ++i) REQUIRE(queue.push(i));
      THEN("the newest 3 remain, in order, and 7 were dropped") {
        const auto c = queue.counters();
        CHECK(c.pushed == 10);
        CHECK(c.dropped == 7);
        CHECK(c.depth == 3);
        CHECK(c.high_water == 3);
        CHECK(queue.pop() == 7);
        CHECK(queue.pop() == 8);
        CHECK(queue.pop() == 9);
        CHECK(queue.counters().popped == 3);
        CHECK(queue.tryPop() == std::nullopt);
      }
    }
  }
}

SCENARIO("A dropped item is destroyed (a frame's buffer goes back to the source)") {
  GIVEN("a queue of capacity 1 holding shared pointers") {
    BoundedQueue<std::shared_ptr<int>> queue(1);
    auto first = std::make_shared<int>(1);
    std::weak_ptr<int> watch = first;
    queue.push(std::move(first));
    WHEN("a second item pushes it out") {
      queue.push(std::make_shared<int>(2));
      THEN("the first item no longer exists") { CHECK(watch.expired()); }
    }
  }
}

SCENARIO("close() ends the stream for consumers and producers") {
  GIVEN("an empty queue and a consumer blocked in pop()") {
    BoundedQueue<int> queue(2);
    std::optional<int> got = 42;
    std::thread consumer([&] { got = queue.pop(); });
    WHEN("the queue is closed") {
      queue.close();
      consumer.join();
      THEN("the consumer wakes with no item, and later pushes are refused and counted") {
        CHECK(got == std::nullopt);
        CHECK_FALSE(queue.push(1));
        CHECK_FALSE(queue.pushWait(2));
        CHECK(queue.counters().refused == 2);
        int out = 0;
        CHECK(queue.popFor(out, std::chrono::milliseconds(1)) == QueueWait::Closed);
      }
    }
  }
  GIVEN("a full queue and a producer blocked in pushWait()") {
    BoundedQueue<int> queue(1);
    queue.push(1);
    bool accepted = true;
    std::thread producer([&] { accepted = queue.pushWait(2); });
    WHEN("the queue is closed") {
      queue.close();
      producer.join();
      THEN("the producer is released with a refusal and the queued item can still be drained") {
        CHECK_FALSE(accepted);
        CHECK(queue.pop() == 1);
        CHECK(queue.pop() == std::nullopt);
      }
    }
  }
  GIVEN("an empty open queue") {
    BoundedQueue<int> queue(1);
    WHEN("popFor times out") {
      int out = 0;
      THEN("it says so") { CHECK(queue.popFor(out, std::chrono::milliseconds(1)) == QueueWait::Timeout); }
    }
  }
}

SCENARIO("Concurrent producers and consumers lose nothing in lossless mode and account for everything in drop mode") {
  constexpr int kPerProducer = 20000;
  for (const bool lossless : {true, false}) {
    GIVEN(std::string(lossless ? "pushWait (lossless)" : "push (drop oldest)")) {
      BoundedQueue<int> queue(4);
      std::atomic<long long> sum{0};
      std::atomic<long long> count{0};
      std::vector<std::thread> threads;
      for (int p = 0; p < 2; ++p)
        threads.emplace_back([&, p] {
          for (int i = 1; i <= kPerProducer; ++i) lossless ? queue.pushWait(i + p * kPerProducer) : queue.push(i);
        });
      std::vector<std::thread> consumers;
      for (int c = 0; c < 2; ++c)
        consumers.emplace_back([&] {
          while (auto v = queue.pop()) {
            sum += *v;
            ++count;
          }
        });
      for (auto& t : threads) t.join();
      queue.close();
      for (auto& t : consumers) t.join();
      const auto c = queue.counters();
      THEN("pushed = popped + dropped, and lossless mode delivered every item exactly once") {
        CHECK(c.pushed == 2 * kPerProducer);
        CHECK(c.pushed == c.popped + c.dropped);
        CHECK(count.load() == c.popped);
        CHECK(c.high_water <= 4);
        if (lossless) {
          const long long n = 2LL * kPerProducer;
          CHECK(c.dropped == 0);
          CHECK(sum.load() == n * (n + 1) / 2);
        }
      }
    }
  }
}

SCENARIO("A queue needs room for at least one item") {
  CHECK_THROWS_AS(BoundedQueue<int>(0), std::invalid_argument);
}

SCENARIO("GIVEN items that must be kept WHEN the queue overflows THEN only droppable items are dropped") {
  // Even numbers stand for records that carry a place: never dropped.
  BoundedQueue<int> queue(3, [](const int& item) { return item % 2 == 0; });
  WHEN("a full queue [0, 1, 2] takes 3, then 4") {
    REQUIRE(queue.push(0));
    REQUIRE(queue.push(1));
    REQUIRE(queue.push(2));
    REQUIRE(queue.push(3));  // drops 1, the oldest droppable
    REQUIRE(queue.push(4));  // drops 3
    THEN("the kept items stay in order and two drops are counted") {
      CHECK(queue.counters().dropped == 2);
      CHECK(queue.pop() == 0);
      CHECK(queue.pop() == 2);
      CHECK(queue.pop() == 4);
    }
  }
  WHEN("the queue is full of kept items and a droppable one arrives") {
    REQUIRE(queue.push(0));
    REQUIRE(queue.push(2));
    REQUIRE(queue.push(4));
    REQUIRE(queue.push(5));
    THEN("the newcomer is the one dropped") {
      const auto c = queue.counters();
      CHECK(c.dropped == 1);
      CHECK(c.pushed == 4);
      CHECK(c.depth == 3);
      CHECK(queue.pop() == 0);
      CHECK(queue.pop() == 2);
      CHECK(queue.pop() == 4);
    }
  }
  WHEN("the queue is full of kept items and another kept one arrives") {
    REQUIRE(queue.push(0));
    REQUIRE(queue.push(2));
    REQUIRE(queue.push(4));
    std::atomic<bool> pushed{false};
    std::thread producer([&] { pushed = queue.push(6); });
    THEN("the producer waits for room instead of dropping, and is counted") {
      CHECK(queue.pop() == 0);  // makes room
      producer.join();
      CHECK(pushed.load());
      const auto c = queue.counters();
      CHECK(c.dropped == 0);
      CHECK(queue.pop() == 2);
      CHECK(queue.pop() == 4);
      CHECK(queue.pop() == 6);
      CHECK(c.kept_waits <= 1);  // 0 if the pop made room before the push
    }
  }
  WHEN("a producer waits on a full queue of kept items and the queue is closed") {
    REQUIRE(queue.push(0));
    REQUIRE(queue.push(2));
    REQUIRE(queue.push(4));
    std::atomic<int> result{-1};
    std::thread producer([&] { result = queue.push(8) ? 1 : 0; });
    queue.close();
    producer.join();
    THEN("the push is refused, not left hanging") {
      CHECK(result.load() == 0);
      CHECK(queue.counters().refused == 1);
    }
  }
}
