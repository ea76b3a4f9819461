#pragma once
// Shared helpers of the libFuzzer targets (fuzz/README.md): a private scratch folder that lives
// as long as the process, files written into it from the input bytes, and the typed-exception
// check (a confluent::Error is the correct answer to bad input; anything else escapes and
// libFuzzer reports it as a crash).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>

#include "core/error.h"

namespace confluent::fuzz {

// A folder of its own, $TMPDIR (or /tmp)/confluent-fuzz-<pid>-XXXXXX. libFuzzer ends with
// _Exit, so the folder outlives the process: each new process first removes the folders of
// processes that are gone.
inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    const std::filesystem::path base = tmp != nullptr && *tmp != '\0' ? tmp : "/tmp";
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(base, error)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("confluent-fuzz-", 0) != 0) continue;
      const long pid = std::atol(name.c_str() + 15);
      if (pid > 0 && !std::filesystem::exists("/proc/" + std::to_string(pid), error))
        std::filesystem::remove_all(entry.path(), error);
    }
    std::string pattern = (base / ("confluent-fuzz-" + std::to_string(getpid()) + "-XXXXXX")).string();
    if (mkdtemp(pattern.data()) == nullptr) {
      std::perror("confluent fuzz: mkdtemp");
      std::abort();
    }
    return std::filesystem::path(pattern);
  }();
  return dir;
}

// Writes `bytes` to ScratchDir()/`name` (folders created) and returns the path.
inline std::string WriteScratch(const std::string& name, std::string_view bytes) {
  const std::filesystem::path path = ScratchDir() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) {
    std::fprintf(stderr, "confluent fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path.string();
}

// Empties ScratchDir() (between inputs of targets that write several files).
inline void ClearScratch() {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(ScratchDir(), error))
    std::filesystem::remove_all(entry.path(), error);
}

// The bytes as a string view.
inline std::string_view Bytes(const uint8_t* data, size_t size) {
  return std::string_view(reinterpret_cast<const char*>(data), size);
}

// Splits at the first NUL byte: the part before and the part after (empty when there is none).
// Targets that need two files take them from one input this way (the seed files hold a NUL).
inline std::pair<std::string_view, std::string_view> SplitAtNul(std::string_view bytes) {
  const size_t nul = bytes.find('\0');
  if (nul == std::string_view::npos) return {bytes, std::string_view()};
  return {bytes.substr(0, nul), bytes.substr(nul + 1)};
}

// Runs `read`; a confluent::Error (InputError, UsageError...) is the expected outcome for bad
// input and is swallowed (printed when CONFLUENT_FUZZ_VERBOSE is set, to check that the seeds
// are read without error). Any other exception escapes to libFuzzer, which reports it.
template <typename Read>
void ExpectTypedErrors(Read&& read) {
  static const bool verbose = std::getenv("CONFLUENT_FUZZ_VERBOSE") != nullptr;
  try {
    read();
    if (verbose) std::fprintf(stderr, "confluent fuzz: read without error\n");
  } catch (const confluent::Error& error) {
    if (verbose) std::fprintf(stderr, "confluent fuzz: %s\n", error.what());
  }
}

}  // namespace confluent::fuzz
