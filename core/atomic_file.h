#pragma once
// Atomic output: write to a temporary file beside the target, then rename over it.

#include <cstddef>
#include <functional>
#include <string>

namespace confluent {

// Creates the parent folders of `path`, calls `write(temporary_path)`, then renames the
// temporary file to `path`. On any failure the temporary file is removed, `path` is left as it
// was, and OutputError naming `path` is thrown.
void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

// Test hook, called by WriteAtomically (and VideoWriter::Close) after the temporary file of
// `path` is fully written and before it is renamed to `path`: when the environment variable
// CONFLUENT_KILL_AT is `SUBSTRING:N` (read once), the process sends itself SIGKILL on the N-th
// such call whose `path` contains SUBSTRING, so tests can kill a run at a chosen, repeatable
// point. Does nothing when the variable is unset or malformed.
void KillHookBeforeRename(const std::string& path);

// The reason for a failed write, from its errno `code`: strerror, and for EFBIG/ENOSPC/EDQUOT
// "(file too large or disk full)"; 0 (unknown) gives a generic guess.
std::string WriteErrorText(int code);

// Writes `size` bytes to `path` directly (no temporary: meant for the temporary path given by
// WriteAtomically), checking every step including fflush and fclose. Throws OutputError naming
// `path` with WriteErrorText's reason.
void WriteFileBytes(const std::string& path, const void* data, std::size_t size);

// Writes `contents` to `path` atomically. Throws OutputError on failure.
void WriteTextFile(const std::string& path, const std::string& contents);

// Reads a whole text file. Throws InputError naming the file if it cannot be read.
std::string ReadTextFile(const std::string& path);

}  // namespace confluent
