// Wavefront OBJ: reading vertices (with optional colours), texture coordinates and polygonal
// faces (fan-triangulated), the diffuse texture from the MTL file, and writing OBJ with its MTL.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mesh_io_internal.h"

namespace confluent {
namespace mesh_io_internal {

namespace {

// Parses the whole of `token` as an int (a leading '+' is allowed).
bool ParseInt(std::string_view token, int* value) {
  const char* begin = token.data();
  const char* end = begin + token.size();
  if (begin < end && *begin == '+') ++begin;
  const auto [ptr, ec] = std::from_chars(begin, end, *value);
  return ec == std::errc() && ptr == end && begin < end;
}

// The diffuse texture named in the MTL file `mtl_path` for `material` (or the first one found),
// resolved to an absolute path; "" when the MTL is missing or names none.
std::string TextureFromMtl(const fs::path& mtl_path, const std::string& material) {
  std::error_code error;
  if (!fs::is_regular_file(mtl_path, error)) return {};
  const std::string text = ReadWholeFile(mtl_path.string());
  std::string current, first_texture, chosen;
  std::vector<std::string_view> tokens;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string_view line = Trim(std::string_view(text).substr(start, end - start));
    start = end + 1;
    SplitTokens(line, &tokens);
    if (tokens.size() < 2) continue;
    if (tokens[0] == "newmtl") {
      current = std::string(Trim(line.substr(6)));
    } else if (tokens[0] == "map_Kd") {
      // Options ("-s 1 1 1 file.png") come first; the file name is then the last token.
      const bool has_options = tokens[1].front() == '-';
      const std::string name(has_options ? tokens.back() : Trim(line.substr(6)));
      if (first_texture.empty()) first_texture = name;
      if (!material.empty() && current == material && chosen.empty()) chosen = name;
    }
  }
  if (chosen.empty()) chosen = first_texture;
  return chosen.empty() ? std::string() : ResolveTexture(chosen, mtl_path);
}

// Resolves a 1-based (or negative, relative) OBJ index against `count` defined so far.
bool ResolveObjIndex(int index, int count, int* resolved) {
  if (index > 0) *resolved = index - 1;
  else if (index < 0) *resolved = count + index;
  else return false;
  return *resolved >= 0 && *resolved < count;
}

}  // namespace

Mesh ReadObj(const std::string& path) {
  const std::string text = ReadWholeFile(path);
  std::vector<double> positions, uvs;
  std::vector<float> colors;
  std::vector<int> faces, face_uvs;
  int num_normals = 0, num_colored = 0;
  bool face_without_uv = false;
  std::string mtllib, first_material;
  std::vector<std::string_view> tokens;
  std::vector<int> corner_v, corner_vt;
  int line_number = 0;
  std::size_t start = 0;
  auto fail = [&](const std::string& problem) -> InputError {
    return InputError(path, "line " + std::to_string(line_number) + ": " + problem);
  };
  while (start < text.size()) {
    const char* line_begin = text.data() + start;
    const void* newline = std::memchr(line_begin, '\n', text.size() - start);
    const std::size_t end = newline ? static_cast<const char*>(newline) - text.data() : text.size();
    std::string_view line(line_begin, end - start);
    start = end + 1;
    ++line_number;
    line = line.substr(0, line.find('#'));  // comments run to the end of the line
    SplitTokens(line, &tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "v") {
      const std::size_t n = tokens.size() - 1;
      if (n != 3 && n != 4 && n != 6 && n != 7)
        throw fail("expected 'v x y z [w]' or 'v x y z r g b', got " + std::to_string(n) + " numbers");
      double values[7];
      for (std::size_t i = 0; i < n; ++i)
        if (!ParseDouble(tokens[i + 1], &values[i])) throw fail("expected a number, got " + Quote(tokens[i + 1]));
      for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(values[i])) throw fail("non-finite vertex coordinate " + Quote(tokens[i + 1]));
        positions.push_back(values[i]);
      }
      if (n >= 6) {
        for (int i = 3; i < 6; ++i) colors.push_back(static_cast<float>(values[i]));
        ++num_colored;
      } else {
        colors.insert(colors.end(), 3, 0.0f);
      }
    } else if (keyword == "vt") {
      if (tokens.size() < 2 || tokens.size() > 4) throw fail("expected 'vt u [v [w]]'");
      double uv[2] = {0.0, 0.0};
      for (std::size_t i = 1; i < tokens.size() && i <= 2; ++i)
        if (!ParseDouble(tokens[i], &uv[i - 1]) || !std::isfinite(uv[i - 1]))
          throw fail("expected a finite number, got " + Quote(tokens[i]));
      uvs.push_back(uv[0]);
      uvs.push_back(uv[1]);
    } else if (keyword == "vn") {
      ++num_normals;
    } else if (keyword == "f") {
      if (tokens.size() < 4) throw fail("a face needs at least 3 vertices");
      corner_v.clear();
      corner_vt.clear();
      const int num_vertices = static_cast<int>(positions.size() / 3);
      const int num_uvs = static_cast<int>(uvs.size() / 2);
      for (std::size_t i = 1; i < tokens.size(); ++i) {
        const std::string_view corner = tokens[i];
        const std::size_t slash1 = corner.find('/');
        const std::string_view v_text = corner.substr(0, slash1);
        std::string_view vt_text, vn_text;
        if (slash1 != std::string_view::npos) {
          const std::size_t slash2 = corner.find('/', slash1 + 1);
          vt_text = corner.substr(slash1 + 1, slash2 == std::string_view::npos ? std::string_view::npos : slash2 - slash1 - 1);
          if (slash2 != std::string_view::npos) vn_text = corner.substr(slash2 + 1);
        }
        int index = 0, resolved = 0;
        if (!ParseInt(v_text, &index)) throw fail("bad face corner " + Quote(corner));
        if (!ResolveObjIndex(index, num_vertices, &resolved))
          throw fail("face index " + std::to_string(index) + " out of range (" + std::to_string(num_vertices) +
                     " vertices so far)");
        corner_v.push_back(resolved);
        if (!vt_text.empty()) {
          if (!ParseInt(vt_text, &index)) throw fail("bad face corner " + Quote(corner));
          if (!ResolveObjIndex(index, num_uvs, &resolved))
            throw fail("texture index " + std::to_string(index) + " out of range (" + std::to_string(num_uvs) +
                       " texture coordinates so far)");
          corner_vt.push_back(resolved);
        }
        if (!vn_text.empty()) {
          if (!ParseInt(vn_text, &index) || !ResolveObjIndex(index, num_normals, &resolved))
            throw fail("bad or out-of-range normal index in " + Quote(corner));
        }
      }
      const bool has_vt = corner_vt.size() == corner_v.size();
      if (!has_vt && !corner_vt.empty()) throw fail("face mixes corners with and without texture index");
      if (!has_vt) face_without_uv = true;
      // Fan triangulation: (0, i, i+1).
      for (std::size_t i = 1; i + 1 < corner_v.size(); ++i) {
        faces.insert(faces.end(), {corner_v[0], corner_v[i], corner_v[i + 1]});
        if (has_vt) face_uvs.insert(face_uvs.end(), {corner_vt[0], corner_vt[i], corner_vt[i + 1]});
      }
    } else if (keyword == "mtllib") {
      if (mtllib.empty()) mtllib = std::string(Trim(line.substr(line.find("mtllib") + 6)));
    } else if (keyword == "usemtl") {
      if (first_material.empty() && tokens.size() >= 2) first_material = std::string(tokens[1]);
    }
    // Everything else (o, g, s, l, p, vp, comments, ...) carries nothing we store.
  }
  Mesh mesh;
  FillMesh(positions, faces, &mesh);
  if (num_colored > 0 && num_colored == mesh.num_vertices())
    mesh.colors = Eigen::Map<const RowMatrixX3f>(colors.data(), mesh.num_vertices(), 3);
  if (!face_without_uv && !face_uvs.empty()) {
    mesh.uvs = Eigen::Map<const RowMatrixX2d>(uvs.data(), static_cast<Eigen::Index>(uvs.size() / 2), 2);
    mesh.face_uvs = Eigen::Map<const RowMatrixX3i>(face_uvs.data(), mesh.num_faces(), 3);
  }
  if (!mtllib.empty()) {
    std::string name = mtllib;
    std::replace(name.begin(), name.end(), '\\', '/');
    fs::path mtl_path = fs::path(path).parent_path() / name;
    std::error_code error;
    // "mtllib a.mtl b.mtl" names several files; use the first.
    if (!fs::exists(mtl_path, error) && name.find(' ') != std::string::npos)
      mtl_path = fs::path(path).parent_path() / name.substr(0, name.find(' '));
    mesh.texture_path = TextureFromMtl(mtl_path, first_material);
  }
  return mesh;
}

void WriteObj(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options) {
  const bool colors = options.write_colors && mesh.has_colors();
  const bool uvs = mesh.has_uvs();
  const bool texture = !mesh.texture_path.empty();
  const fs::path obj_path(path);
  const std::string mtl_name = obj_path.stem().string() + ".mtl";
  std::string out;
  out.reserve(static_cast<std::size_t>(mesh.num_vertices()) * 40 + static_cast<std::size_t>(mesh.num_faces()) * 30);
  out += "# written by confluent\n";
  if (texture) {
    std::string mtl = "# written by confluent\nnewmtl material0\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd ";
    mtl += RelativeOrAbsolute(mesh.texture_path, obj_path.parent_path()) + "\n";
    WriteTextFile((obj_path.parent_path() / mtl_name).string(), mtl);
    out += "mtllib " + mtl_name + "\nusemtl material0\n";
  }
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    out += "v ";
    for (int k = 0; k < 3; ++k) {
      if (k > 0) out += ' ';
      AppendNumber(&out, mesh.vertices(i, k));
    }
    if (colors)
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        AppendNumber(&out, mesh.colors(i, k));
      }
    out += '\n';
  }
  if (uvs)
    for (Eigen::Index i = 0; i < mesh.uvs.rows(); ++i) {
      out += "vt ";
      AppendNumber(&out, mesh.uvs(i, 0));
      out += ' ';
      AppendNumber(&out, mesh.uvs(i, 1));
      out += '\n';
    }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      AppendInt(&out, mesh.faces(f, k) + 1);
      if (uvs) {
        out += '/';
        AppendInt(&out, mesh.face_uvs(f, k) + 1);
      }
    }
    out += '\n';
  }
  WriteAtomically(path, [&](const std::string& temporary) { WriteBytes(temporary, out); });
}

}  // namespace mesh_io_internal
}  // namespace confluent
