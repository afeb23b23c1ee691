// Test helper of tests/platform/files: a fresh temporary folder, removed when the test ends.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace toposlam::test {

struct TempFolder {
  std::filesystem::path path;
  /// `name` keeps the folders of different tests apart; the process id, parallel runs.
  explicit TempFolder(const std::string& name)
      : path(std::filesystem::temp_directory_path() / ("toposlam-files-" + name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
};

}  // namespace toposlam::test
