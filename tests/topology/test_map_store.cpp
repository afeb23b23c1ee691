// Tests of MapStore's format: a filter state cut or flipped anywhere throws or loads, never crashes; a
// frozen state encodes the map of its moment. The map on disk (atomic save, .prev, recovery, the lock, a
// full disk) is tested with the file functions, in tests/pipeline/test_map_files.cpp.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fake_similarity.hpp"
#include "toposlam/topology/map_store.hpp"

using namespace toposlam;
using toposlam::test::placeSimilarity;
using toposlam::test::smallFilter;
using toposlam::test::taggedFingerprint;

TEST_CASE(
    "GIVEN every truncation and byte flips of a filter state WHEN loaded THEN it throws or loads, never "
    "crashes",
    "[topology][map]") {
  auto sim = placeSimilarity();
  auto filter = smallFilter(sim, 9);
  std::ostringstream out;
  filter->saveState(out);
  const std::string state = out.str();
  REQUIRE(state.size() > 100);
  // The state ends with the likelihood block (u8 + 3 f64), the new-node block (u8) and the new-node floor
  // block (f64). A state cut just before one is one written before that block existed: before the likelihood
  // block it loads with the thesis' absolute likelihood, before the new-node block with eq. 5.7's entropy,
  // before the floor block with no floor. Every other cut throws.
  constexpr std::size_t kFloorBlock = 8;
  constexpr std::size_t kNewNodeBlock = 1;
  constexpr std::size_t kLikelihoodBlock = 1 + 3 * 8;
  for (std::size_t cut = 0; cut < state.size(); ++cut) {
    std::istringstream in(state.substr(0, cut));
    if (cut == state.size() - kFloorBlock - kNewNodeBlock - kLikelihoodBlock) {
      CHECK(TopologyParticleFilter::loadState(in, sim)->config().likelihood == LikelihoodModel::Absolute);
      continue;
    }
    if (cut == state.size() - kFloorBlock - kNewNodeBlock) {
      const auto loaded = TopologyParticleFilter::loadState(in, sim);
      CHECK(loaded->config().new_node_entropy);
      CHECK(loaded->config().new_node_likelihood_floor == 0.0);
      continue;
    }
    if (cut == state.size() - kFloorBlock) {
      CHECK(TopologyParticleFilter::loadState(in, sim)->config().new_node_likelihood_floor == 0.0);
      continue;
    }
    CHECK_THROWS_AS(TopologyParticleFilter::loadState(in, sim), std::runtime_error);
  }
  // Flips in the filter's own fields: the config (first 53 bytes) and the particles and history records
  // (the last 300 bytes). Fingerprint blobs are left alone: readFingerprint's own robustness is tested by
  // the fingerprint module, and MapStore's checksum refuses any flipped file before parsing.
  std::vector<std::size_t> positions;
  for (std::size_t p = 0; p < 53; ++p) positions.push_back(p);
  for (std::size_t p = state.size() - 300; p < state.size(); ++p) positions.push_back(p);
  constexpr std::size_t kForbidReturnByte = 4 + 4 * 8 + 2 * 4;  // after i32 + 4 f64 + 2 i32 of the config
  REQUIRE(state[kForbidReturnByte] == 0);  // default false; a flip makes it 0x5a: damage, refused
  int loaded = 0, refused = 0;
  for (std::size_t position : positions) {
    std::string flipped = state;
    flipped[position] = static_cast<char>(flipped[position] ^ 0x5a);
    std::istringstream in(flipped);
    try {
      auto f = TopologyParticleFilter::loadState(in, sim);
      // Whatever loads holds exactly what the file said (the flip is kept, nothing silently repaired
      // or dropped) and is usable.
      CHECK(position != kForbidReturnByte);
      std::ostringstream again;
      f->saveState(again);
      INFO("flipped byte " << position << " of " << state.size());
      CHECK(again.str() == flipped);
      f->step(taggedFingerprint(1));
      ++loaded;
    } catch (const std::runtime_error&) {
      ++refused;
    }
  }
  INFO("loaded " << loaded << ", refused " << refused << " of " << positions.size());
  // Measured: 66 flips load (and re-save exactly), 287 are refused (the flag byte among them). The last 300
  // bytes include the likelihood block, whose slope, offset and floor load whenever they stay in range, and
  // the new node's likelihood floor (0 here): a flip of one of its 7 low bytes is a tiny floor in [0, 1)
  // and loads, of its top byte a huge one and is refused (before that block: 59 and 294).
  // A change in either count means the loader's validation changed: look at which flips moved.
  CHECK(loaded == 66);
  CHECK(refused == 287);
}

TEST_CASE("GIVEN a filter without eq. 5.7's entropy or with a new node's likelihood floor WHEN saved and loaded "
          "THEN the loaded one keeps them",
          "[topology][map]") {
  auto sim = placeSimilarity();
  for (const bool entropy : {false, true}) {
    TopologyFilterConfig config;
    config.particles = 50;
    config.likelihood = LikelihoodModel::Relative;
    config.new_node_entropy = entropy;
    config.new_node_likelihood_floor = entropy ? 0.0 : 0.01;
    TopologyParticleFilter filter(config, sim);
    for (int k = 0; k < 6; ++k) filter.step(taggedFingerprint(k % 3));
    std::ostringstream out;
    filter.saveState(out);
    std::istringstream in(out.str());
    auto loaded = TopologyParticleFilter::loadState(in, sim);
    CHECK(loaded->config().new_node_entropy == entropy);
    CHECK(loaded->config().new_node_likelihood_floor == config.new_node_likelihood_floor);
    // The loaded filter steps as the original does.
    filter.step(taggedFingerprint(1));
    loaded->step(taggedFingerprint(1));
    std::ostringstream a, b;
    filter.saveState(a);
    loaded->saveState(b);
    CHECK(a.str() == b.str());
  }
}

TEST_CASE("GIVEN a filter frozen between steps WHEN it goes on stepping while another thread encodes the "
          "frozen state THEN that encodes exactly the map of the moment it was frozen",
          "[topology][map][reliability]") {
  // The daemon's map snapshot (issue 19): frozen on the topology thread (pointer copies), encoded on the map
  // writer thread while the filter goes on. One representative per node, so later steps drop stored
  // fingerprints the frozen state must keep alive.
  auto sim = placeSimilarity();
  TopologyFilterConfig c;
  c.particles = 50;
  c.seed = 5;
  c.max_representatives_per_node = 1;
  TopologyParticleFilter filter(c, sim);
  for (int k = 0; k < 12; ++k) filter.step(taggedFingerprint(k % 4));
  const std::string at_freeze = MapStore::encode(filter, "frames 1 2 3", {{"keypoints", "orb"}});
  const FrozenTopologyState frozen = filter.freeze();
  CHECK(frozen.observationCount() == 12);

  std::string encoded_meanwhile;
  std::thread writer([&] { encoded_meanwhile = MapStore::encode(frozen, "frames 1 2 3", {{"keypoints", "orb"}}); });
  for (int k = 0; k < 24; ++k) filter.step(taggedFingerprint(k % 6));
  writer.join();

  CHECK(encoded_meanwhile == at_freeze);
  CHECK(MapStore::encode(frozen, "frames 1 2 3", {{"keypoints", "orb"}}) == at_freeze);
  CHECK(MapStore::encode(filter, "frames 1 2 3", {{"keypoints", "orb"}}) != at_freeze);
  const LoadedMap loaded = MapStore::decode(at_freeze, sim);
  CHECK(loaded.filter->observationCount() == 12);
  CHECK(filter.observationCount() == 36);

  filter.beginStep(taggedFingerprint(1));
  CHECK_THROWS_AS(filter.freeze(), std::logic_error);  // not in the middle of a step
}

TEST_CASE(
    "GIVEN a map path WHEN the store names the files beside it THEN .prev, damaged copies and "
    "temporaries are named and recognised without touching the disk",
    "[topology][map]") {
  const std::filesystem::path map = "state/map.tsm";
  CHECK(MapStore::previousPath(map) == std::filesystem::path("state/map.tsm.prev"));
  CHECK(MapStore::recoveryCandidates(map) ==
        std::vector<std::filesystem::path>{"state/map.tsm", "state/map.tsm.prev"});
  CHECK(MapStore::probePath("state/.map.tsm.Ab3dE9") == "state/.map.tsm.Ab3dE9.probe");
  CHECK(MapStore::isTemporaryOf(map, ".map.tsm.Ab3dE9"));
  CHECK(MapStore::isTemporaryOf(map, ".map.tsm.Zz0000.prev"));
  CHECK(MapStore::isTemporaryOf(map, ".map.tsm.Zz0000.probe"));
  for (const char* other : {"map.tsm", "map.tsm.prev", ".map.tsm.lock", ".map.tsm.toolong7",
                            ".other.tsm.Ab3dE9", ".map.tsm.Ab3d-9", ".map.tsm.Ab3dE9.next"})
    CHECK_FALSE(MapStore::isTemporaryOf(map, other));

  CHECK(MapStore::damagedPath(map, "20240131T120501", 0) ==
        std::filesystem::path("state/map.tsm.damaged-20240131T120501"));
  CHECK(MapStore::damagedPath(map, "20240131T120501", 2) ==
        std::filesystem::path("state/map.tsm.damaged-20240131T120501-2"));
  CHECK(MapStore::isDamagedCopyOf(map, "map.tsm.damaged-20240131T120501-2"));
  CHECK_FALSE(MapStore::isDamagedCopyOf(map, "map.tsm.prev.damaged-20240131T120501"));
  std::vector<std::filesystem::path> copies;
  for (const char* stamp : {"20240131T120502", "20240131T120501-1", "20240131T120501", "20240201T000000",
                            "20240131T120503", "20240131T120504", "20240131T120501-2"})
    copies.push_back(std::string("state/map.tsm.damaged-") + stamp);
  CHECK(MapStore::damagedCopiesToRemove(copies) ==
        std::vector<std::filesystem::path>{"state/map.tsm.damaged-20240131T120501",
                                           "state/map.tsm.damaged-20240131T120501-1"});
  copies.resize(kMaxDamagedFiles);
  CHECK(MapStore::damagedCopiesToRemove(copies).empty());
}

TEST_CASE(
    "GIVEN a map file image WHEN its framing is checked piece by piece THEN only the intact image verifies",
    "[topology][map]") {
  auto sim = placeSimilarity();
  const std::string image = MapStore::encode(*smallFilter(sim, 6), "data");
  auto verifies = [](const std::string& bytes, std::size_t piece) {
    MapFramingCheck check;
    if (!check.start(std::string_view(bytes).substr(0, kMapHeaderSize), bytes.size())) return false;
    REQUIRE(check.payloadSize() == bytes.size() - kMapHeaderSize);
    for (std::size_t at = kMapHeaderSize; at < bytes.size(); at += piece)
      check.add(bytes.data() + at, std::min(piece, bytes.size() - at));
    return check.verified();
  };
  CHECK(verifies(image, 1));
  CHECK(verifies(image, 1000));
  std::string flipped = image;
  flipped[image.size() / 2] = static_cast<char>(flipped[image.size() / 2] ^ 0x10);
  CHECK_FALSE(verifies(flipped, 1000));
  CHECK_FALSE(verifies(image + "x", 1000));  // the file is longer than its header says
  std::string newer = image;
  newer[8] = static_cast<char>(kMapFormatVersion + 1);
  CHECK_FALSE(verifies(newer, 1000));
  CHECK_FALSE(MapFramingCheck().start("TSLMAP", 6));  // shorter than a header
}

namespace {

/// The map image `image` as format 4 wrote it: the same filter, application data and settings, no views.
std::string withoutViews(const std::string& image) {
  constexpr std::size_t kHeader = 32;
  std::size_t at = kHeader;
  for (int field = 0; field < 3; ++field) {  // bytes(filter state), bytes(application data), bytes(settings)
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i) size |= std::uint64_t{static_cast<unsigned char>(image[at + i])} << (8 * i);
    at += 8 + size;
  }
  std::string payload = image.substr(kHeader, at - kHeader);
  std::string out = image.substr(0, 8);
  const auto put = [&out](std::uint64_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
  };
  put(4, 4);
  put(0, 4);
  put(payload.size(), 8);
  put(mapPayloadChecksum(4, payload), 8);
  return out + payload;
}

}  // namespace

TEST_CASE("GIVEN a map with its places' views WHEN saved and loaded THEN every place keeps its views, and a map "
          "of format 4 loads with none",
          "[topology][map]") {
  auto sim = placeSimilarity();
  auto filter = smallFilter(sim, 5);
  REQUIRE(filter->observationCount() == 5);
  PlaceViews views(3);  // shorter than the observations: the rest have none
  views[0] = {taggedFingerprint(1), taggedFingerprint(2)};
  views[2] = {taggedFingerprint(3)};
  const std::string image = MapStore::encode(*filter, "data", {{"keypoints", "orb"}}, views);
  const LoadedMap loaded = MapStore::decode(image, sim);
  REQUIRE(loaded.views.size() == 5);
  CHECK(loaded.views[0].size() == 2);
  CHECK(loaded.views[0][1]->image_width == 3);
  CHECK(loaded.views[1].empty());
  CHECK(loaded.views[2].size() == 1);
  CHECK(loaded.views[3].empty());
  CHECK(loaded.views[4].empty());
  CHECK(loaded.application_data == "data");
  // Without views the image is the one a map without them always gave.
  CHECK(MapStore::encode(*filter, "data", {{"keypoints", "orb"}}) ==
        MapStore::encode(*filter, "data", {{"keypoints", "orb"}}, PlaceViews(5)));
  CHECK(image.size() > MapStore::encode(*filter, "data", {{"keypoints", "orb"}}).size());
  // Format 4 had no views: it loads, each place with none.
  const LoadedMap old = MapStore::decode(withoutViews(image), sim);
  CHECK(old.filter->observationCount() == 5);
  CHECK(old.views.size() == 5);
  CHECK(std::all_of(old.views.begin(), old.views.end(), [](const auto& v) { return v.empty(); }));
  CHECK(old.settings.at("keypoints") == "orb");
  // A version 5 image whose views section was cut is damaged, named so.
  CHECK_THROWS_WITH(MapStore::decode(withoutViews(image).replace(8, 1, 1, '\x05'), sim),
                    Catch::Contains("damaged") || Catch::Contains("checksum"));
}
