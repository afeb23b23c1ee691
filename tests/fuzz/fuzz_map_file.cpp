// libFuzzer target: the map file decoder (MapStore::decode). Input byte 0 picks the mode: odd = the rest
// is a payload, framed here with a correct header and checksum (so the fuzzer reaches the filter-state
// parser instead of stopping at the checksum); even = the rest is a whole file image. Anything but a
// MapStoreError is a finding.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/topology/map_store.hpp"

namespace {

void putLe(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const toposlam::NgramSimilarity similarity;
  const std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  std::string file;
  if (data[0] & 1) {
    file = std::string("TSLMAP\r\n", 8);
    putLe(file, toposlam::kMapFormatVersion, 4);
    putLe(file, 0, 4);
    putLe(file, rest.size(), 8);
    putLe(file, toposlam::mapPayloadChecksum(toposlam::kMapFormatVersion, rest), 8);
    file += rest;
  } else {
    file = std::string(rest);
  }
  try {
    toposlam::LoadedMap loaded = toposlam::MapStore::decode(file, similarity, "fuzz");
    // Whatever loads must encode again (a usable filter).
    (void)toposlam::MapStore::encode(*loaded.filter, loaded.application_data, loaded.settings);
  } catch (const toposlam::MapStoreError&) {
  }
  return 0;
}
