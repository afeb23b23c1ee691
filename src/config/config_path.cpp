// The default config look-up of toposlamd, `toposlam listen` and toposlam-bridge (config_path.hpp).
#include "toposlam/config/config_path.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace toposlam {

namespace {

// The running program's file, "" when /proc does not say.
std::string runningExecutable() {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::string() : exe.string();
}

}  // namespace

std::string installSysconfDir(const std::string& executable) {
  const std::filesystem::path exe = std::filesystem::path(executable).lexically_normal();
  if (!exe.is_absolute()) return "";
  const std::filesystem::path dir = exe.parent_path();
  if (dir.filename() != "bin" && dir.filename() != "sbin") return "";
  const std::string prefix = dir.parent_path().string();
  if (prefix == "/" || prefix == "/usr") return "/etc";
  if (prefix.rfind("/opt/", 0) == 0 && prefix.size() > 5) return "/etc" + prefix;
  return prefix + "/etc";
}

std::vector<std::string> configPathCandidates(const std::string& file_name, const std::string& executable) {
  std::vector<std::string> candidates;
  if (const char* dir = std::getenv("CONFIGURATION_DIRECTORY"); dir != nullptr && dir[0] != '\0') {
    std::string first(dir);
    first = first.substr(0, first.find(':'));  // several ConfigurationDirectory= entries are colon-separated
    candidates.push_back((std::filesystem::path(first) / file_name).string());
  }
  if (const std::string sysconf = installSysconfDir(executable); !sysconf.empty() && sysconf != "/etc")
    candidates.push_back((std::filesystem::path(sysconf) / "toposlam" / file_name).string());
  candidates.push_back("/etc/toposlam/" + file_name);
  return candidates;
}

std::string defaultConfigPath(const std::string& file_name) {
  const std::vector<std::string> candidates = configPathCandidates(file_name, runningExecutable());
  for (const std::string& c : candidates)
    if (std::filesystem::exists(c)) return c;
  return candidates.front();
}

std::string defaultDaemonConfigPath() { return defaultConfigPath("toposlam.yaml"); }

}  // namespace toposlam
