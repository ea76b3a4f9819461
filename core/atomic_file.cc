#include "core/atomic_file.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace confluent {
namespace fs = std::filesystem;

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
  fs::rename(temporary, target, error);
  if (error) {
    fs::remove(temporary, error);
    throw OutputError(path, "cannot rename temporary file: " + error.message());
  }
}

void WriteTextFile(const std::string& path, const std::string& contents) {
  WriteAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << contents;
    out.flush();
    if (!out) throw OutputError(temporary, "write failed (disk full or no permission?)");
  });
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, fs::exists(path) ? "cannot be read" : "no such file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace confluent
