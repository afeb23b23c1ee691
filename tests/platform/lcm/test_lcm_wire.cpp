// Tests of lcmArrayLengthsFit: a message whose array length is negative or far beyond its own size is
// refused before the generated decoder allocates for it (a place_t claiming 10^8 alternatives used to
// allocate 800 MB; a negative one killed `toposlam listen` with bad_alloc).
#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam_lcm/place_t.hpp"
#include "toposlam_lcm/status_t.hpp"
#include "toposlam_lcm/topology_t.hpp"

using namespace toposlam;

namespace {

template <typename Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  return bytes;
}

void putInt32(std::vector<std::uint8_t>& bytes, std::size_t at, std::int32_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  for (int i = 0; i < 4; ++i) bytes.at(at + static_cast<std::size_t>(i)) = static_cast<std::uint8_t>(u >> (24 - 8 * i));
}

}  // namespace

TEST_CASE("GIVEN encoded place, status and topology messages WHEN checked THEN they fit, and lying lengths do not",
          "[platform][lcm][reliability]") {
  toposlam_lcm::place_t place{};
  place.num_alternatives = 2;
  place.alternatives.resize(2);
  std::vector<std::uint8_t> bytes = encode(place);
  CHECK(lcmArrayLengthsFit("place", bytes.data(), bytes.size()));
  const std::size_t length_at = 8 + 8 * 3 + 4 * 4 + 1 + 4;  // hash, then the fixed fields before the length
  for (std::int32_t lie : {-1, 3, 100'000'000, INT32_MIN}) {
    std::vector<std::uint8_t> bad = bytes;
    putInt32(bad, length_at, lie);
    INFO("num_alternatives = " << lie);
    CHECK_FALSE(lcmArrayLengthsFit("place", bad.data(), bad.size()));
  }
  CHECK_FALSE(lcmArrayLengthsFit("place", bytes.data(), bytes.size() - 1));  // truncated
  // A place message as recorded before match_* existed (place_v1_t): 20 bytes shorter, its own schema.
  CHECK_FALSE(lcmArrayLengthsFit("place", bytes.data(), bytes.size() - 20));
  CHECK(lcmArrayLengthsFit("place_v1", bytes.data(), bytes.size() - 20));
  CHECK_FALSE(lcmArrayLengthsFit("no-such-kind", bytes.data(), bytes.size()));

  toposlam_lcm::status_t status{};
  status.state = "running";
  status.source_state = "streaming";
  status.num_stages = 1;
  status.stages.resize(1);
  status.stages[0].name = "capture";
  const std::vector<std::uint8_t> status_bytes = encode(status);
  CHECK(lcmArrayLengthsFit("status", status_bytes.data(), status_bytes.size()));
  std::vector<std::uint8_t> bad_string = status_bytes;
  putInt32(bad_string, 8 + 8, -5);  // the state string's length
  CHECK_FALSE(lcmArrayLengthsFit("status", bad_string.data(), bad_string.size()));
  // Length 0 (no room even for the NUL): the generated decoder would assign -1 bytes (found by
  // fuzz_lcm_messages).
  putInt32(bad_string, 8 + 8, 0);
  CHECK_FALSE(lcmArrayLengthsFit("status", bad_string.data(), bad_string.size()));

  toposlam_lcm::topology_t topology{};
  topology.num_nodes = 1;
  topology.nodes.resize(1);
  topology.nodes[0].num_places = 2;
  topology.nodes[0].places = {0, 1};
  topology.nodes[0].num_representatives = 1;
  topology.nodes[0].representative_frames = {7};
  topology.num_edges = 1;
  topology.edges.resize(1);
  std::vector<std::uint8_t> topo_bytes = encode(topology);
  CHECK(lcmArrayLengthsFit("topology", topo_bytes.data(), topo_bytes.size()));
  putInt32(topo_bytes, 8 + 8 + 8 + 8 + 4 + 4 + 4 + 4, 1'000'000'000);  // node 0's num_places
  CHECK_FALSE(lcmArrayLengthsFit("topology", topo_bytes.data(), topo_bytes.size()));
}
