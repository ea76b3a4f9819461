#pragma once
// A temporary folder for a benchmark's synthesised inputs, removed with everything in it when the
// program ends.

#include <filesystem>
#include <string>
#include <system_error>
#include <unistd.h>

namespace confluent {

struct ScratchFolder {
  explicit ScratchFolder(const std::string& prefix)
      : path(std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()))) {}
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  std::filesystem::path path;
};

}  // namespace confluent
