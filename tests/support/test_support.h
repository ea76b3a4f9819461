#pragma once
// Helpers shared by the gtest suites: temporary folders, the confluent binary, shared data.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"

namespace confluent::testing {

// Expects `options.Check()` to throw a UsageError whose message contains `expected`.
template <typename Options>
void ExpectCheckRefuses(const Options& options, const std::string& expected) {
  try {
    options.Check();
    ADD_FAILURE() << "accepted; expected: " << expected;
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
  }
}

// A fresh empty folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// Result of running the confluent binary.
struct CommandResult {
  int exit_code = -1;
  std::string stdout_text;
  std::string stderr_text;
};

// Runs the `confluent` binary of this build (or $CONFLUENT_BIN) with `args`. `shell_prefix`
// is run by the same shell just before it (e.g. "ulimit -f 100;" to simulate a full disk).
CommandResult RunConfluent(const std::vector<std::string>& args, const std::string& shell_prefix = "");

// Runs a shell command and returns its stdout ("" when it could not run).
std::string CaptureOutput(const std::string& shell_command);

// Extracts the real samba mesh sequence (shared data meshseq/vlasic_samba.tar.xz) into `dir` and
// returns its .obj files in name order; empty when the archive is not available. Throws
// std::runtime_error when the archive is present but cannot be extracted.
std::vector<std::string> ExtractSambaSequence(const std::string& dir);

// Writes `text` to `path` (binary, so bytes go through unchanged), creating its parent folders.
void WriteFile(const std::string& path, const std::string& text);

// Number of files in `dir` whose extension is `extension` (".png"); 0 when `dir` is not a folder.
int CountFiles(const std::string& dir, const std::string& extension);

// Absolute path of ../shared/data/<relative>, or "" when it does not exist. Tests call
// GTEST_SKIP() with a message when this is empty.
std::string SharedDataPath(const std::string& relative);

}  // namespace confluent::testing
