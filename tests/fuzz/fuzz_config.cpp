// libFuzzer target: the YAML config reader (parseDaemonConfig). Anything but a ConfigError is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "toposlam/config/daemon_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;  // the loader caps files at 1 MiB; small inputs explore faster
  try {
    (void)toposlam::parseDaemonConfig(std::string(reinterpret_cast<const char*>(data), size), "fuzz");
  } catch (const toposlam::ConfigError&) {
  }
  return 0;
}
