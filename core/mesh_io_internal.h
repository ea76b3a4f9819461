// Internal to core/: the helpers the mesh readers and writers share (defined in mesh_io.cc) and
// the per-format entry points ReadMesh and WriteMesh dispatch to: OBJ (with its MTL texture) in
// mesh_io_obj.cc, PLY (ASCII and binary) in mesh_io_ply.cc. Not part of the module's interface.
#pragma once

#include <charconv>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh_io.h"

namespace confluent {
namespace mesh_io_internal {

namespace fs = std::filesystem;

// The whole file as bytes; InputError when it is missing or unreadable.
std::string ReadWholeFile(const std::string& path);

bool IsSpace(char c);

// Parses the whole of `token` as a double (a leading '+' is allowed).
bool ParseDouble(std::string_view token, double* value);

std::string Quote(std::string_view token);

// Appends the shortest text that reads back as exactly `value`.
template <typename T>
void AppendNumber(std::string* out, T value) {
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, result.ptr);
}

void AppendInt(std::string* out, long long value);

// Writes `bytes` to `path` (called on the temporary file of WriteAtomically).
void WriteBytes(const std::string& path, const std::string& bytes);

// `target` relative to the folder `base` when possible (both made absolute), else absolute.
std::string RelativeOrAbsolute(const std::string& target, const fs::path& base);

// Resolves a texture file name found in `referencing_file` to an absolute, normal path.
std::string ResolveTexture(std::string name, const fs::path& referencing_file);

std::string_view Trim(std::string_view text);

// Splits `line` at whitespace into `tokens` (views into `line`).
void SplitTokens(std::string_view line, std::vector<std::string_view>* tokens);

// Copies flat vectors into the mesh's Eigen matrices.
void FillMesh(const std::vector<double>& positions, const std::vector<int>& faces, Mesh* mesh);

Mesh ReadObj(const std::string& path);
void WriteObj(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options);
Mesh ReadPly(const std::string& path);
void WritePly(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options);

}  // namespace mesh_io_internal
}  // namespace confluent
