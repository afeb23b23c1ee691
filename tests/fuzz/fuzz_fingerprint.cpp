// libFuzzer target: fingerprint deserialisation (readFingerprint, "VPK1"). Anything but a
// std::runtime_error is a finding; what reads must validate and write back the same bytes it consumed.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

#include "toposlam/fingerprint/fingerprint.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const toposlam::Fingerprint f = toposlam::readFingerprint(in);
    std::ostringstream out;
    toposlam::writeFingerprint(out, f);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
