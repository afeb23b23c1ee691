// libFuzzer target: LCM log files (`toposlam listen --from lcmlog:FILE`, `toposlam report lcmlog:FILE`). Any
// bytes either read as a run or fail with LcmLogError (naming the offset); nothing else may escape, and no
// length in a header makes the reader allocate more than the file holds.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "toposlam/platform/lcm_log.hpp"
#include "toposlam/platform/lcm_log_run.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > (1u << 20)) return 0;
  // The reader takes a file, as the commands give it: one per process, rewritten for each input.
  static const std::string path = "/tmp/fuzz_lcm_log." + std::to_string(getpid());
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return 0;
  const bool written = std::fwrite(data, 1, size, file) == size;
  std::fclose(file);
  if (!written) return 0;
  try {
    const toposlam::LoggedRun run = toposlam::readLoggedRun(path, toposlam::LcmChannels{});
    if (run.events < 0 || static_cast<std::size_t>(run.events) * toposlam::kLcmLogHeaderBytes > size) std::abort();
  } catch (const toposlam::LcmLogError&) {
    // a clear error: expected for damaged input
  } catch (...) {
    std::abort();
  }
  std::remove(path.c_str());
  return 0;
}
