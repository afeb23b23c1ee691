// StatusCollector alone: plain numbers in, the PipelineStatus the publisher would send out.
#include <catch2/catch.hpp>

#include "toposlam/pipeline/status_collector.hpp"

using namespace toposlam;

namespace {

StatusCounters countersOf(double cpu_s, std::int64_t dropped, double process_cpu_s) {
  StatusCounters c;
  c.stages.resize(3);
  c.stages[1].processed = 40;
  c.stages[1].input.dropped = dropped;
  c.stages[1].input.kept_waits = 2;
  c.stages[1].input.depth = 3;
  c.stages[1].input.capacity = 8;
  c.stages[1].cpu_s = cpu_s;
  c.stages[2].input.dropped = 1;
  c.process_cpu_s = process_cpu_s;
  c.frames_captured = 50;
  c.source_link = SourceLink::Reconnecting;
  c.source_reconnect_attempts = 2;
  c.places = 4;
  c.map_revision = 7;
  c.maps_saved = 1;
  return c;
}

}  // namespace

SCENARIO("GIVEN two seconds of published frames WHEN the status is collected THEN rates, latencies and totals are "
         "the period's") {
  StatusCollector collector({"capture", "fingerprint", "publisher"}, 10.0, 10.0, 100.0);
  for (int f = 1; f <= 40; ++f) {
    collector.addStageMs(1, static_cast<double>(f));  // 1 .. 40 ms
    collector.addPublished(2.0 * f);
  }
  CHECK_FALSE(collector.due(10.5, 1.0));
  REQUIRE(collector.due(12.0, 1.0));
  const PipelineStatus s = collector.collect(12.0, "running", countersOf(0.5, 5, 101.0));
  CHECK(s.time_s == 12.0);
  CHECK(s.uptime_s == 2.0);
  CHECK(s.fps == 20.0);
  CHECK(s.frames_published == 40);
  CHECK(s.frames_captured == 50);
  CHECK(s.latency.samples == 40);
  CHECK(s.latency.median_ms == 41.0);
  CHECK(s.latency.max_ms == 80.0);
  REQUIRE(s.stages.size() == 3);
  CHECK(s.stages[1].name == "fingerprint");
  CHECK(s.stages[1].latency.median_ms == 20.5);
  CHECK(s.stages[1].latency.p99_ms == 40.0);
  CHECK(s.stages[1].processed == 40);
  CHECK(s.stages[1].queue_depth == 3);
  CHECK(s.stages[1].queue_capacity == 8);
  CHECK(s.stages[1].cpu_percent == 25.0);  // 0.5 s of CPU over 2 s
  CHECK(s.stages[0].latency.samples == 0);
  CHECK(s.frames_dropped == 6);
  CHECK(s.queue_kept_waits == 2);
  CHECK(s.cpu_percent == 50.0);  // 1 s of the process's CPU over 2 s
  CHECK(s.source_link == SourceLink::Reconnecting);
  CHECK(s.source_reconnect_attempts == 2);
  CHECK(s.places == 4);
  CHECK(s.map_revision == 7);
  CHECK(s.maps_saved == 1);
  CHECK(s.state == "running");

  THEN("the next period starts empty and its rates count from the last status") {
    collector.addPublished(1.0);
    const PipelineStatus next = collector.collect(13.0, "finished", countersOf(0.75, 5, 101.5));
    CHECK(next.fps == 1.0);
    CHECK(next.frames_published == 41);
    CHECK(next.latency.samples == 1);
    CHECK(next.stages[1].latency.samples == 0);
    CHECK(next.stages[1].cpu_percent == 25.0);  // 0.25 s over 1 s
    CHECK(next.cpu_percent == 50.0);
    CHECK(next.state == "finished");
  }
}
