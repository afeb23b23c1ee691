// Test helpers for tests that touch files: a fresh temporary folder removed when the test ends, a file's
// bytes, the number of entries in a folder.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
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

/// The whole file's bytes ("" when it cannot be read).
inline std::string readAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

/// Entries directly in `dir`.
inline std::size_t filesIn(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

}  // namespace toposlam::test
