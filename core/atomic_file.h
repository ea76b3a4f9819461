#pragma once
// Atomic output: write to a temporary file beside the target, then rename over it.

#include <functional>
#include <string>

namespace confluent {

// Creates the parent folders of `path`, calls `write(temporary_path)`, then renames the
// temporary file to `path`. On any failure the temporary file is removed, `path` is left as it
// was, and OutputError naming `path` is thrown.
void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

// Writes `contents` to `path` atomically. Throws OutputError on failure.
void WriteTextFile(const std::string& path, const std::string& contents);

// Reads a whole text file. Throws InputError naming the file if it cannot be read.
std::string ReadTextFile(const std::string& path);

}  // namespace confluent
