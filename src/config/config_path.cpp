// The default config look-up of toposlamd and `toposlam listen` (config_path.hpp).
#include "toposlam/config/config_path.hpp"

#include <cstdlib>
#include <filesystem>
#include <vector>

#ifndef TOPOSLAM_INSTALLED_CONFIG
#define TOPOSLAM_INSTALLED_CONFIG "/etc/toposlam/toposlam.yaml"
#endif

namespace toposlam {

std::string defaultDaemonConfigPath() {
  std::vector<std::string> candidates;
  if (const char* dir = std::getenv("CONFIGURATION_DIRECTORY"); dir != nullptr && dir[0] != '\0') {
    std::string first(dir);
    first = first.substr(0, first.find(':'));  // several ConfigurationDirectory= entries are colon-separated
    candidates.push_back((std::filesystem::path(first) / "toposlam.yaml").string());
  }
  candidates.push_back("/etc/toposlam/toposlam.yaml");
  candidates.push_back(TOPOSLAM_INSTALLED_CONFIG);
  for (const std::string& c : candidates)
    if (std::filesystem::exists(c)) return c;
  return candidates.front();
}

}  // namespace toposlam
