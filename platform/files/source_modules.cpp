// Loadable source modules: see source_modules.hpp.
#include "source_modules.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <vector>

#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> moduleFolders() {
  if (const char* explicit_dir = std::getenv("TOPOSLAM_MODULE_DIR"); explicit_dir && *explicit_dir)
    return {explicit_dir};
  std::vector<std::string> folders;
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  if (!error)
    folders.push_back(
        (program.parent_path().parent_path() / TOPOSLAM_MODULE_INSTALL_DIR).lexically_normal().string());
  folders.push_back(TOPOSLAM_MODULE_BUILD_DIR);
  return folders;
}

struct LoadedModules {
  std::mutex mutex;
  std::map<std::string, void*> handles;  // never closed: sources made by a module may outlive any caller
};

LoadedModules& loadedModules() {
  static LoadedModules modules;
  return modules;
}

}  // namespace

void* sourceModuleSymbol(const std::string& name, const std::string& symbol) {
  const std::string file = "toposlam-source-" + name + ".so";
  LoadedModules& modules = loadedModules();
  const std::lock_guard lock(modules.mutex);
  void*& handle = modules.handles[name];
  if (!handle) {
    std::string searched;
    for (const std::string& folder : moduleFolders()) {
      const fs::path candidate = fs::path(folder) / file;
      searched += (searched.empty() ? "" : ", ") + folder;
      std::error_code error;
      if (!fs::exists(candidate, error)) continue;
      handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        const char* why = dlerror();
        throw FrameSourceError(name + ": cannot load " + candidate.string() + ": " +
                               (why ? why : "unknown error"));
      }
      break;
    }
    if (!handle)
      throw FrameSourceError(name + ": the module " + file + " is not installed (looked in " + searched +
                             "; TOPOSLAM_MODULE_DIR names another folder)");
  }
  dlerror();
  void* address = dlsym(handle, symbol.c_str());
  if (!address) {
    const char* why = dlerror();
    throw FrameSourceError(name + ": " + file + " has no " + symbol +
                           " (a module of another toposlam version?): " + (why ? why : "symbol not found"));
  }
  return address;
}

}  // namespace toposlam
