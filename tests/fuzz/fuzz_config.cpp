// libFuzzer target: the YAML config reader (parseDaemonConfig). Anything but a ConfigError is a finding, and
// so is an accepted input whose document holds an alias (*name): aliases are refused before the document is
// built (issue 41: a 1 KB alias bomb hung start-up), so no accepted config may contain one. The seeds
// (corpus/config) include alias bombs, nested aliases, merge keys (<<) and octal-looking numbers.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include "toposlam/config/daemon_config.hpp"

namespace {

// Counts the aliases of the first document from yaml-cpp's events (nothing is expanded).
class AliasCounter final : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override { ++aliases; }
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
  int aliases = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;  // the loader caps files at 1 MiB; small inputs explore faster
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)toposlam::parseDaemonConfig(text, "fuzz");
  } catch (const toposlam::ConfigError&) {
    return 0;
  }
  // Accepted: its document must hold no alias.
  std::istringstream in(text);
  YAML::Parser parser(in);
  AliasCounter counter;
  parser.HandleNextDocument(counter);
  if (counter.aliases > 0) std::abort();
  return 0;
}
