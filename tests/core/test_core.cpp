// Core utilities: natural ordering, the worker pool, the JSON writer.
#include <algorithm>
#include <atomic>
#include <mutex>
#include <vector>
#include <sstream>

#include <catch2/catch.hpp>

#include "toposlam/core/json_writer.hpp"
#include "toposlam/core/natural_order.hpp"
#include "toposlam/core/worker_pool.hpp"

using namespace toposlam;

TEST_CASE("GIVEN numbered file names WHEN sorted naturally THEN 2 comes before 10") {
  std::vector<std::string> names = {"10.jpg", "2.jpg", "1.jpg", "84.jpg", "09.jpg", "a.jpg", "img12b", "img12a"};
  sortNatural(names);
  CHECK(names == std::vector<std::string>{"1.jpg", "2.jpg", "09.jpg", "10.jpg", "84.jpg", "a.jpg", "img12a",
                                          "img12b"});
  CHECK(naturalLess("frame_000099.png", "frame_000100.png"));
  CHECK_FALSE(naturalLess("x", "x"));
}

TEST_CASE("GIVEN a pool WHEN a batch runs THEN every task runs exactly once, for several batches") {
  for (int workers : {1, 2, 4}) {
    WorkerPool pool(workers);
    CHECK(pool.size() == workers);
    for (int batch = 0; batch < 50; ++batch) {
      std::vector<std::atomic<int>> hits(37);
      pool.run(hits.size(), [&](std::size_t i) { hits[i].fetch_add(1); });
      for (auto& h : hits) REQUIRE(h.load() == 1);
    }
  }
}

TEST_CASE("GIVEN a pool with a start hook WHEN it is built THEN each extra worker runs the hook once, numbered 1 .. N-1") {
  std::mutex mutex;
  std::vector<int> started;
  {
    WorkerPool pool(4, [&](int worker) {
      std::lock_guard lock(mutex);
      started.push_back(worker);
    });
    std::atomic<int> hits{0};
    pool.run(8, [&](std::size_t) { hits.fetch_add(1); });
    CHECK(hits.load() == 8);
  }  // joined: every hook has run
  std::sort(started.begin(), started.end());
  CHECK(started == std::vector<int>{1, 2, 3});
}

TEST_CASE("GIVEN a failing task WHEN the batch runs THEN the error reaches the caller after the batch") {
  WorkerPool pool(2);
  std::atomic<int> done{0};
  CHECK_THROWS_WITH(pool.run(10,
                             [&](std::size_t i) {
                               if (i == 3) throw std::runtime_error("task 3 failed");
                               done.fetch_add(1);
                             }),
                    "task 3 failed");
  CHECK(done.load() == 9);
  CHECK_THROWS_AS(WorkerPool(0), std::invalid_argument);
}

TEST_CASE("GIVEN nested values WHEN written as JSON THEN the text is valid and escaped") {
  std::ostringstream out;
  JsonWriter json(out, false);
  json.beginObject().field("name", "a\"b\n").field("n", 3).field("x", 0.5).field("ok", true);
  json.key("list").beginArray().value(1).value(2).endArray();
  json.key("empty").beginObject().endObject();
  json.endObject();
  CHECK(out.str() == R"({"name":"a\"b\n","n":3,"x":0.5,"ok":true,"list":[1,2],"empty":{}})");
}
