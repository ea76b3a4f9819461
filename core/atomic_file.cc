#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace confluent {
namespace fs = std::filesystem;

std::string WriteErrorText(int code) {
  if (code == EFBIG || code == ENOSPC || code == EDQUOT) return "file too large or disk full (" + std::string(std::strerror(code)) + ")";
  if (code == 0) return "disk full or no permission?";
  return std::strerror(code);
}

void KillHookBeforeRename(const std::string& path) {
  struct KillAt {
    std::string substring;  // empty: the hook is off
    long count = 0;
  };
  static const KillAt kill_at = [] {
    KillAt parsed;
    const char* value = std::getenv("CONFLUENT_KILL_AT");
    if (value == nullptr) return parsed;
    const std::string text(value);
    const std::size_t colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0) return parsed;
    char* end = nullptr;
    const long count = std::strtol(text.c_str() + colon + 1, &end, 10);
    if (end == text.c_str() + colon + 1 || *end != '\0' || count < 1) return parsed;
    parsed.substring = text.substr(0, colon);
    parsed.count = count;
    return parsed;
  }();
  if (kill_at.substring.empty() || path.find(kill_at.substring) == std::string::npos) return;
  static std::atomic<long> seen{0};  // writes that matched so far (masks are written by several threads)
  if (++seen == kill_at.count) std::raise(SIGKILL);
}

void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  std::error_code error;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), error);
    if (error) throw OutputError(path, "cannot create folder " + target.parent_path().string() + ": " + error.message());
  }
  // Keep the extension last so format-by-extension writers (OIIO, OpenCV) still work.
  const std::string temporary =
      (target.parent_path() / (".tmp" + std::to_string(getpid()) + "_" + target.filename().string())).string();
  try {
    write(temporary);
  } catch (const OutputError& failure) {
    fs::remove(temporary, error);
    throw OutputError(path, failure.problem());
  } catch (...) {
    fs::remove(temporary, error);
    throw;
  }
  if (!fs::exists(temporary, error)) throw OutputError(path, "writing failed (no output was produced)");
  KillHookBeforeRename(path);
  fs::rename(temporary, target, error);
  if (error) {
    fs::remove(temporary, error);
    throw OutputError(path, "cannot rename temporary file: " + error.message());
  }
}

void WriteFileBytes(const std::string& path, const void* data, std::size_t size) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw OutputError(path, std::string("cannot open for writing: ") + std::strerror(errno));
  errno = 0;
  const std::size_t written = std::fwrite(data, 1, size, file);
  const bool failed = written != size || std::fflush(file) != 0;
  const int write_errno = errno;
  errno = 0;
  const bool close_failed = std::fclose(file) != 0;
  if (failed || close_failed) throw OutputError(path, "write failed: " + WriteErrorText(failed ? write_errno : errno));
}

void WriteTextFile(const std::string& path, const std::string& contents) {
  WriteAtomically(path, [&](const std::string& temporary) { WriteFileBytes(temporary, contents.data(), contents.size()); });
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, fs::exists(path) ? "cannot be read" : "no such file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace confluent
