#include "tests/support/test_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace confluent::testing {
namespace fs = std::filesystem;

TempDir::TempDir() {
  std::random_device random;
  for (int attempt = 0; attempt < 100; ++attempt) {
    fs::path candidate = fs::temp_directory_path() /
                         ("confluent_test_" + std::to_string(getpid()) + "_" + std::to_string(random()));
    if (fs::create_directory(candidate)) {
      path_ = candidate.string();
      return;
    }
  }
  std::abort();
}

TempDir::~TempDir() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

namespace {
std::string ShellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}
std::string Slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}
}  // namespace

CommandResult RunConfluent(const std::vector<std::string>& args, const std::string& shell_prefix) {
  const char* binary = std::getenv("CONFLUENT_BIN");
  if (binary == nullptr) binary = CONFLUENT_DEFAULT_BIN;
  CommandResult result;
  TempDir scratch;
  std::string command = shell_prefix + " exec " + ShellQuote(binary);
  for (const auto& arg : args) command += " " + ShellQuote(arg);
  command += " </dev/null >" + scratch / "out" + " 2>" + scratch / "err";
  int status = std::system(command.c_str());
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.stdout_text = Slurp(scratch / "out");
  result.stderr_text = Slurp(scratch / "err");
  return result;
}

std::string CaptureOutput(const std::string& shell_command) {
  std::string output;
  FILE* pipe = popen(shell_command.c_str(), "r");
  if (pipe == nullptr) return output;
  char buffer[256];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) output += buffer;
  pclose(pipe);
  return output;
}

std::vector<std::string> ExtractSambaSequence(const std::string& dir) {
  const std::string archive = SharedDataPath("meshseq/vlasic_samba.tar.xz");
  if (archive.empty()) return {};
  if (std::system(("tar xJf " + ShellQuote(archive) + " -C " + ShellQuote(dir)).c_str()) != 0)
    throw std::runtime_error("cannot extract " + archive);
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.path().extension() == ".obj") files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

void WriteFile(const std::string& path, const std::string& text) {
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty()) fs::create_directories(parent);
  std::ofstream out(path, std::ios::binary);
  out << text;
}

int CountFiles(const std::string& dir, const std::string& extension) {
  if (!fs::is_directory(dir)) return 0;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) count += entry.path().extension() == extension;
  return count;
}

std::string SharedDataPath(const std::string& relative) {
  const char* root = std::getenv("CONFLUENT_SHARED_DATA");
  fs::path base = root ? fs::path(root) : fs::path(CONFLUENT_DEFAULT_SHARED_DATA);
  fs::path full = base / relative;
  std::error_code error;
  if (!fs::exists(full, error)) return {};
  return fs::absolute(full).string();
}

}  // namespace confluent::testing
