#include "core/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mesh_io_internal.h"

namespace confluent {
namespace mesh_io_internal {

// The whole file as bytes; InputError when it is missing or unreadable.
std::string ReadWholeFile(const std::string& path) {
  std::error_code error;
  if (!fs::exists(path, error)) throw InputError(path, "no such file");
  if (fs::is_directory(path, error)) throw InputError(path, "is a folder, not a mesh file");
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw InputError(path, std::string("cannot be read: ") + std::strerror(errno));
  std::string data;
  char chunk[1 << 16];
  const std::uintmax_t size = fs::file_size(path, error);
  if (!error) data.reserve(static_cast<std::size_t>(size));
  std::size_t got = 0;
  while ((got = std::fread(chunk, 1, sizeof(chunk), file)) > 0) data.append(chunk, got);
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) throw InputError(path, "read error");
  return data;
}

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Parses the whole of `token` as a double (a leading '+' is allowed).
bool ParseDouble(std::string_view token, double* value) {
  const char* begin = token.data();
  const char* end = begin + token.size();
  if (begin < end && *begin == '+') ++begin;
  const auto [ptr, ec] = std::from_chars(begin, end, *value);
  return ec == std::errc() && ptr == end && begin < end;
}

std::string Quote(std::string_view token) {
  std::string text(token.substr(0, 40));
  if (token.size() > 40) text += "...";
  return "'" + text + "'";
}

void AppendInt(std::string* out, long long value) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, result.ptr);
}

// Writes `bytes` to `path` (called on the temporary file of WriteAtomically).
void WriteBytes(const std::string& path, const std::string& bytes) { WriteFileBytes(path, bytes.data(), bytes.size()); }

// `target` relative to the folder `base` when possible (both made absolute), else absolute.
std::string RelativeOrAbsolute(const std::string& target, const fs::path& base) {
  const fs::path absolute_target = fs::absolute(target).lexically_normal();
  const fs::path relative = absolute_target.lexically_relative(fs::absolute(base).lexically_normal());
  return relative.empty() ? absolute_target.string() : relative.generic_string();
}

// Resolves a texture file name found in `referencing_file` to an absolute, normal path.
std::string ResolveTexture(std::string name, const fs::path& referencing_file) {
  std::replace(name.begin(), name.end(), '\\', '/');
  fs::path texture(name);
  if (texture.is_relative()) texture = referencing_file.parent_path() / texture;
  return fs::absolute(texture).lexically_normal().string();
}

std::string_view Trim(std::string_view text) {
  while (!text.empty() && IsSpace(text.front())) text.remove_prefix(1);
  while (!text.empty() && IsSpace(text.back())) text.remove_suffix(1);
  return text;
}

// Splits `line` at whitespace into `tokens` (views into `line`).
void SplitTokens(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !IsSpace(line[i])) ++i;
    if (i > start) tokens->push_back(line.substr(start, i - start));
  }
}

// Copies flat vectors into the mesh's Eigen matrices.
void FillMesh(const std::vector<double>& positions, const std::vector<int>& faces, Mesh* mesh) {
  mesh->vertices = Eigen::Map<const RowMatrixX3d>(positions.data(), static_cast<Eigen::Index>(positions.size() / 3), 3);
  mesh->faces = Eigen::Map<const RowMatrixX3i>(faces.data(), static_cast<Eigen::Index>(faces.size() / 3), 3);
}

}  // namespace mesh_io_internal

namespace {

using namespace mesh_io_internal;

std::string LowerExtension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

}  // namespace

Mesh ReadMesh(const std::string& path) {
  const std::string extension = LowerExtension(path);
  if (extension != ".obj" && extension != ".ply")
    throw InputError(path, "unknown mesh file extension '" + extension + "' (expected .obj or .ply)");
  try {
    return extension == ".obj" ? ReadObj(path) : ReadPly(path);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& failure) {
    // Internal parse problems (bad list lengths, allocation failures) still name the file.
    throw InputError(path, failure.what());
  }
}

void WriteMesh(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options) {
  const std::string extension = LowerExtension(path);
  if (extension != ".obj" && extension != ".ply")
    throw OutputError(path, "unknown mesh file extension '" + extension + "' (expected .obj or .ply)");
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.faces(f, k) < 0 || mesh.faces(f, k) >= mesh.num_vertices())
        throw OutputError(path, "face " + std::to_string(f) + " has an out-of-range vertex index");
  if (mesh.has_uvs())
    for (int f = 0; f < mesh.num_faces(); ++f)
      for (int k = 0; k < 3; ++k)
        if (mesh.face_uvs(f, k) < 0 || mesh.face_uvs(f, k) >= mesh.uvs.rows())
          throw OutputError(path, "face " + std::to_string(f) + " has an out-of-range uv index");
  if (extension == ".obj") WriteObj(path, mesh, options);
  else WritePly(path, mesh, options);
}

}  // namespace confluent
