// PLY: reading ASCII and binary (either endianness) files, with vertex colours, per-vertex or
// per-corner texture coordinates, face labels and the TextureFile comment, and writing them.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mesh_io_internal.h"

namespace confluent {
namespace mesh_io_internal {

namespace {

enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

bool ParsePlyType(std::string_view name, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},       {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},   {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16}, {"uint16", PlyType::kUInt16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUInt32},     {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [text, value] : kNames)
    if (name == text) {
      *type = value;
      return true;
    }
  return false;
}

std::size_t PlyTypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8: case PlyType::kUInt8: return 1;
    case PlyType::kInt16: case PlyType::kUInt16: return 2;
    case PlyType::kInt32: case PlyType::kUInt32: case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 0;
}

// Reads PLY body values one at a time, in any of the three formats.
class PlyBodyReader {
 public:
  PlyBodyReader(const std::string& path, const std::string& text, std::size_t offset, PlyFormat format,
                int header_lines)
      : path_(path), data_(text.data() + offset), end_(text.data() + text.size()), format_(format),
        line_(header_lines + 1) {}

  // Where we are, for error messages ("vertex 12" or "face 3").
  void SetLocation(const std::string& element, std::size_t index) {
    element_ = &element;
    index_ = index;
  }

  // The next value, converted to double.
  double Read(PlyType type) {
    if (format_ == PlyFormat::kAscii) return ReadAscii();
    const std::size_t size = PlyTypeSize(type);
    if (static_cast<std::size_t>(end_ - data_) < size)
      throw InputError(path_, "truncated: the file ends inside " + *element_ + " " + std::to_string(index_));
    unsigned char bytes[8];
    std::memcpy(bytes, data_, size);
    data_ += size;
    if (format_ == PlyFormat::kBinaryBigEndian) std::reverse(bytes, bytes + size);
    switch (type) {
      case PlyType::kInt8: return Load<std::int8_t>(bytes);
      case PlyType::kUInt8: return Load<std::uint8_t>(bytes);
      case PlyType::kInt16: return Load<std::int16_t>(bytes);
      case PlyType::kUInt16: return Load<std::uint16_t>(bytes);
      case PlyType::kInt32: return Load<std::int32_t>(bytes);
      case PlyType::kUInt32: return Load<std::uint32_t>(bytes);
      case PlyType::kFloat32: return Load<float>(bytes);
      case PlyType::kFloat64: return Load<double>(bytes);
    }
    return 0.0;
  }

  // Reads and discards one property (scalar or list).
  void Skip(const PlyProperty& property) {
    if (!property.is_list) {
      Read(property.type);
      return;
    }
    const std::size_t count = ReadCount(property);
    if (format_ != PlyFormat::kAscii) {
      const std::size_t bytes = count * PlyTypeSize(property.type);
      if (static_cast<std::size_t>(end_ - data_) < bytes)
        throw InputError(path_, "truncated: the file ends inside " + *element_ + " " + std::to_string(index_));
      data_ += bytes;
      return;
    }
    for (std::size_t i = 0; i < count; ++i) Read(property.type);
  }

  // The length prefix of a list property; InputError if negative or absurd.
  std::size_t ReadCount(const PlyProperty& property) {
    const double count = Read(property.count_type);
    if (!(count >= 0 && count < 1e6 && count == std::floor(count)))
      Fail("bad list length " + std::to_string(count) + " in property '" + property.name + "'");
    return static_cast<std::size_t>(count);
  }

  // Prefix for error messages about the current value.
  std::string Where() const {
    if (format_ == PlyFormat::kAscii) return "line " + std::to_string(line_) + ": ";
    return *element_ + " " + std::to_string(index_) + ": ";
  }

  [[noreturn]] void Fail(const std::string& problem) const { throw InputError(path_, Where() + problem); }

 private:
  template <typename T>
  static double Load(const unsigned char* bytes) {
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return static_cast<double>(value);
  }

  double ReadAscii() {
    while (data_ < end_ && IsSpace(*data_)) {
      if (*data_ == '\n') ++line_;
      ++data_;
    }
    if (data_ >= end_)
      throw InputError(path_, "truncated: the file ends inside " + *element_ + " " + std::to_string(index_));
    const char* start = data_;
    while (data_ < end_ && !IsSpace(*data_)) ++data_;
    double value = 0.0;
    const std::string_view token(start, static_cast<std::size_t>(data_ - start));
    if (!ParseDouble(token, &value)) Fail("expected a number, got " + Quote(token));
    return value;
  }

  const std::string& path_;
  const char* data_;
  const char* end_;
  PlyFormat format_;
  int line_;
  const std::string* element_ = nullptr;
  std::size_t index_ = 0;
};

int FindProperty(const PlyElement& element, std::initializer_list<const char*> names) {
  for (const char* name : names)
    for (std::size_t i = 0; i < element.properties.size(); ++i)
      if (element.properties[i].name == name) return static_cast<int>(i);
  return -1;
}

// Scale that maps a colour of `type` to [0,1].
float ColorScale(PlyType type) {
  switch (type) {
    case PlyType::kUInt8: return 1.0f / 255.0f;
    case PlyType::kUInt16: return 1.0f / 65535.0f;
    case PlyType::kFloat32: case PlyType::kFloat64: return 1.0f;
    default: return 1.0f / 255.0f;
  }
}

}  // namespace

Mesh ReadPly(const std::string& path) {
  const std::string text = ReadWholeFile(path);
  // --- header
  std::size_t position = 0;
  int header_lines = 0;
  auto next_header_line = [&](std::string_view* line) {
    if (position >= text.size()) return false;
    std::size_t end = text.find('\n', position);
    if (end == std::string::npos) end = text.size();
    *line = Trim(std::string_view(text).substr(position, end - position));
    position = end + 1;
    ++header_lines;
    return true;
  };
  auto header_error = [&](const std::string& problem) {
    return InputError(path, "line " + std::to_string(header_lines) + ": " + problem);
  };
  std::string_view line;
  if (!next_header_line(&line) || line != "ply") throw InputError(path, "not a PLY file (no 'ply' on the first line)");
  PlyFormat format = PlyFormat::kAscii;
  bool have_format = false, have_end = false;
  std::vector<PlyElement> elements;
  std::string texture_file;
  std::vector<std::string_view> tokens;
  while (next_header_line(&line)) {
    SplitTokens(line, &tokens);
    if (tokens.empty()) continue;
    if (tokens[0] == "end_header") {
      have_end = true;
      break;
    }
    if (tokens[0] == "comment" || tokens[0] == "obj_info") {
      // MeshLab convention: "comment TextureFile name.png".
      if (tokens.size() >= 3 && tokens[0] == "comment" && tokens[1] == "TextureFile")
        texture_file = std::string(Trim(line.substr(line.find("TextureFile") + 11)));
    } else if (tokens[0] == "format") {
      if (tokens.size() < 2) throw header_error("incomplete format line");
      if (tokens[1] == "ascii") format = PlyFormat::kAscii;
      else if (tokens[1] == "binary_little_endian") format = PlyFormat::kBinaryLittleEndian;
      else if (tokens[1] == "binary_big_endian") format = PlyFormat::kBinaryBigEndian;
      else throw header_error("unknown format " + Quote(tokens[1]));
      have_format = true;
    } else if (tokens[0] == "element") {
      double count = 0;
      if (tokens.size() != 3 || !ParseDouble(tokens[2], &count) || count < 0 || count != std::floor(count) ||
          count > 2e9)
        throw header_error("expected 'element NAME COUNT'");
      elements.push_back({std::string(tokens[1]), static_cast<std::size_t>(count), {}});
    } else if (tokens[0] == "property") {
      if (elements.empty()) throw header_error("property before any element");
      PlyProperty property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        property.is_list = true;
        if (!ParsePlyType(tokens[2], &property.count_type) || !ParsePlyType(tokens[3], &property.type))
          throw header_error("unknown property type in " + Quote(line));
        property.name = std::string(tokens[4]);
      } else if (tokens.size() == 3) {
        if (!ParsePlyType(tokens[1], &property.type)) throw header_error("unknown property type " + Quote(tokens[1]));
        property.name = std::string(tokens[2]);
      } else {
        throw header_error("expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
      }
      elements.back().properties.push_back(property);
    } else {
      throw header_error("unknown header keyword " + Quote(tokens[0]));
    }
  }
  if (!have_end) throw InputError(path, "truncated header (no end_header)");
  if (!have_format) throw InputError(path, "header has no format line");

  // Each element needs at least this many bytes, so a corrupt count cannot make us allocate
  // far more memory than the file could ever fill.
  std::size_t minimum_body_bytes = 0;
  for (const auto& element : elements) {
    std::size_t per_element = 0;
    for (const auto& property : element.properties)
      per_element += format == PlyFormat::kAscii ? 1 : PlyTypeSize(property.is_list ? property.count_type : property.type);
    minimum_body_bytes += per_element * element.count;
  }
  if (minimum_body_bytes > text.size() - std::min(position, text.size()))
    throw InputError(path, "truncated: the header declares more data than the file holds (" +
                               std::to_string(text.size() - std::min(position, text.size())) + " bytes after the header)");

  // --- the layout of the elements we understand
  const PlyElement* vertex_element = nullptr;
  for (const auto& element : elements)
    if (element.name == "vertex") vertex_element = &element;
  if (vertex_element == nullptr) throw InputError(path, "no vertex element");
  const int x = FindProperty(*vertex_element, {"x"}), y = FindProperty(*vertex_element, {"y"}),
            z = FindProperty(*vertex_element, {"z"});
  if (x < 0 || y < 0 || z < 0) throw InputError(path, "vertex element lacks x, y or z");
  for (int p : {x, y, z})
    if (vertex_element->properties[p].is_list) throw InputError(path, "vertex x, y, z must not be lists");
  const std::size_t num_vertices = vertex_element->count;
  if (num_vertices > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InputError(path, "too many vertices");

  Mesh mesh;
  std::vector<double> positions(num_vertices * 3);
  std::vector<float> colors;
  std::vector<double> uvs;
  std::vector<int> faces, face_uvs;
  std::vector<int> labels;
  std::vector<int> polygon;
  std::vector<double> polygon_uv;
  PlyBodyReader reader(path, text, position, format, header_lines);

  for (const PlyElement& element : elements) {
    if (&element == vertex_element) {
      // Slot per property: 0..2 position, 3..5 colour, 6..7 per-vertex uv, -1 ignored.
      std::vector<int> slot(element.properties.size(), -1);
      slot[x] = 0;
      slot[y] = 1;
      slot[z] = 2;
      const int color[3] = {FindProperty(element, {"red", "r", "diffuse_red"}),
                            FindProperty(element, {"green", "g", "diffuse_green"}),
                            FindProperty(element, {"blue", "b", "diffuse_blue"})};
      float color_scale[3] = {1, 1, 1};
      const bool has_color = color[0] >= 0 && color[1] >= 0 && color[2] >= 0;
      if (has_color) {
        for (int k = 0; k < 3; ++k) {
          if (element.properties[color[k]].is_list) throw InputError(path, "vertex colours must not be lists");
          slot[color[k]] = 3 + k;
          color_scale[k] = ColorScale(element.properties[color[k]].type);
        }
        colors.resize(num_vertices * 3);
      }
      const int u = FindProperty(element, {"u", "s", "texture_u"}), v = FindProperty(element, {"v", "t", "texture_v"});
      const bool has_uv = u >= 0 && v >= 0 && !element.properties[u].is_list && !element.properties[v].is_list;
      if (has_uv) {
        slot[u] = 6;
        slot[v] = 7;
        uvs.resize(num_vertices * 2);
      }
      for (std::size_t i = 0; i < num_vertices; ++i) {
        reader.SetLocation(element.name, i);
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
          const int s = slot[p];
          if (s < 0) {
            reader.Skip(element.properties[p]);
            continue;
          }
          const double value = reader.Read(element.properties[p].type);
          if (s < 3) {
            if (!std::isfinite(value)) reader.Fail("vertex " + std::to_string(i) + " has a non-finite coordinate");
            positions[i * 3 + s] = value;
          } else if (s < 6) {
            colors[i * 3 + (s - 3)] = static_cast<float>(value) * color_scale[s - 3];
          } else {
            uvs[i * 2 + (s - 6)] = value;
          }
        }
      }
      if (has_uv) {
        mesh.uvs = Eigen::Map<const RowMatrixX2d>(uvs.data(), static_cast<Eigen::Index>(num_vertices), 2);
        uvs.clear();
      }
    } else if (element.name == "face") {
      const int indices = FindProperty(element, {"vertex_indices", "vertex_index"});
      if (indices < 0 || !element.properties[indices].is_list)
        throw InputError(path, "face element lacks a vertex_indices list");
      const int label = FindProperty(element, {"label"});
      const bool has_label = label >= 0 && !element.properties[label].is_list;
      const int texcoord = FindProperty(element, {"texcoord"});
      const bool has_texcoord = texcoord >= 0 && element.properties[texcoord].is_list;
      faces.reserve(element.count * 3);
      if (has_label) labels.reserve(element.count);
      bool texcoords_complete = has_texcoord;
      for (std::size_t f = 0; f < element.count; ++f) {
        reader.SetLocation(element.name, f);
        int face_label = 0;
        polygon.clear();
        polygon_uv.clear();
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
          const PlyProperty& property = element.properties[p];
          if (static_cast<int>(p) == indices) {
            const std::size_t count = reader.ReadCount(property);
            for (std::size_t k = 0; k < count; ++k) {
              const double index = reader.Read(property.type);
              if (!(index >= 0 && index < static_cast<double>(num_vertices))) {
                char shown[32];  // printed from the double: the value may not fit any integer type
                std::snprintf(shown, sizeof shown, "%.15g", index);
                reader.Fail("face " + std::to_string(f) + " has vertex index " + shown + " out of range (" +
                            std::to_string(num_vertices) + " vertices)");
              }
              polygon.push_back(static_cast<int>(index));
            }
            if (count < 3) reader.Fail("face " + std::to_string(f) + " has fewer than 3 vertices");
          } else if (has_label && static_cast<int>(p) == label) {
            const double value = reader.Read(property.type);
            if (!(std::abs(value) <= std::numeric_limits<int>::max()))
              reader.Fail("label " + std::to_string(value) + " is not an int");
            face_label = static_cast<int>(value);
          } else if (has_texcoord && static_cast<int>(p) == texcoord) {
            const std::size_t count = reader.ReadCount(property);
            for (std::size_t k = 0; k < count; ++k) polygon_uv.push_back(reader.Read(property.type));
          } else {
            reader.Skip(property);
          }
        }
        if (has_texcoord && polygon_uv.size() != 2 * polygon.size()) texcoords_complete = false;
        for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
          faces.insert(faces.end(), {polygon[0], polygon[k], polygon[k + 1]});
          if (has_label) labels.push_back(face_label);
          if (texcoords_complete) {
            for (std::size_t corner : {std::size_t{0}, k, k + 1}) {
              face_uvs.push_back(static_cast<int>(uvs.size() / 2));
              uvs.push_back(polygon_uv[2 * corner]);
              uvs.push_back(polygon_uv[2 * corner + 1]);
            }
          }
        }
      }
      if (texcoords_complete && !faces.empty()) {
        mesh.uvs = Eigen::Map<const RowMatrixX2d>(uvs.data(), static_cast<Eigen::Index>(uvs.size() / 2), 2);
        mesh.face_uvs = Eigen::Map<const RowMatrixX3i>(face_uvs.data(), static_cast<Eigen::Index>(face_uvs.size() / 3), 3);
      }
    } else if (!element.properties.empty()) {  // an element without properties has no data
      for (std::size_t i = 0; i < element.count; ++i) {
        reader.SetLocation(element.name, i);
        for (const auto& property : element.properties) reader.Skip(property);
      }
    }
  }
  FillMesh(positions, faces, &mesh);
  if (!colors.empty()) mesh.colors = Eigen::Map<const RowMatrixX3f>(colors.data(), mesh.num_vertices(), 3);
  // Per-vertex uvs (u, v properties) index the vertices directly.
  if (mesh.uvs.rows() == mesh.num_vertices() && mesh.face_uvs.rows() == 0 && mesh.num_vertices() > 0)
    mesh.face_uvs = mesh.faces;
  if (!labels.empty()) mesh.face_labels = std::move(labels);
  if (!texture_file.empty()) mesh.texture_path = ResolveTexture(texture_file, path);
  return mesh;
}

namespace {

template <typename T>
void AppendBinary(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  // PLY binary output is little-endian; convert on big-endian hosts.
  if constexpr (sizeof(T) > 1) {
    const std::uint16_t probe = 1;
    unsigned char first;
    std::memcpy(&first, &probe, 1);
    if (first == 0) std::reverse(bytes, bytes + sizeof(T));
  }
  out->append(bytes, sizeof(T));
}

std::uint8_t ColorByte(float value) {
  const float clamped = std::min(1.0f, std::max(0.0f, std::isfinite(value) ? value : 0.0f));
  return static_cast<std::uint8_t>(std::lround(clamped * 255.0f));
}

}  // namespace

void WritePly(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options) {
  const bool binary = options.binary;
  const bool doubles = options.double_precision;
  const bool colors = options.write_colors && mesh.has_colors();
  const bool labels = options.write_face_labels && mesh.has_face_labels();
  const bool uvs = mesh.has_uvs();
  const int n = mesh.num_vertices(), m = mesh.num_faces();
  std::string out;
  out.reserve(256 + static_cast<std::size_t>(n) * (binary ? 27 : 60) + static_cast<std::size_t>(m) * (binary ? 41 : 40));
  out += "ply\nformat ";
  out += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  out += "comment written by confluent\n";
  if (!mesh.texture_path.empty())
    out += "comment TextureFile " + RelativeOrAbsolute(mesh.texture_path, fs::path(path).parent_path()) + "\n";
  out += "element vertex " + std::to_string(n) + "\n";
  const char* coordinate_type = doubles ? "double" : "float";
  for (const char* axis : {"x", "y", "z"}) out += std::string("property ") + coordinate_type + " " + axis + "\n";
  if (colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "element face " + std::to_string(m) + "\nproperty list uchar int vertex_indices\n";
  if (labels) out += "property int label\n";
  if (uvs) out += "property list uchar float texcoord\n";
  out += "end_header\n";
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double value = mesh.vertices(i, k);
      if (binary) {
        if (doubles) AppendBinary(&out, value);
        else AppendBinary(&out, static_cast<float>(value));
      } else {
        if (k > 0) out += ' ';
        if (doubles) AppendNumber(&out, value);
        else AppendNumber(&out, static_cast<float>(value));
      }
    }
    if (colors)
      for (int k = 0; k < 3; ++k) {
        const std::uint8_t byte = ColorByte(mesh.colors(i, k));
        if (binary) {
          AppendBinary(&out, byte);
        } else {
          out += ' ';
          AppendInt(&out, byte);
        }
      }
    if (!binary) out += '\n';
  }
  for (int f = 0; f < m; ++f) {
    if (binary) {
      AppendBinary(&out, std::uint8_t{3});
      for (int k = 0; k < 3; ++k) AppendBinary(&out, static_cast<std::int32_t>(mesh.faces(f, k)));
      if (labels) AppendBinary(&out, static_cast<std::int32_t>(mesh.face_labels[f]));
      if (uvs) {
        AppendBinary(&out, std::uint8_t{6});
        for (int k = 0; k < 3; ++k)
          for (int c = 0; c < 2; ++c) AppendBinary(&out, static_cast<float>(mesh.uvs(mesh.face_uvs(f, k), c)));
      }
    } else {
      out += '3';
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        AppendInt(&out, mesh.faces(f, k));
      }
      if (labels) {
        out += ' ';
        AppendInt(&out, mesh.face_labels[f]);
      }
      if (uvs) {
        out += " 6";
        for (int k = 0; k < 3; ++k)
          for (int c = 0; c < 2; ++c) {
            out += ' ';
            AppendNumber(&out, static_cast<float>(mesh.uvs(mesh.face_uvs(f, k), c)));
          }
      }
      out += '\n';
    }
  }
  WriteAtomically(path, [&](const std::string& temporary) { WriteBytes(temporary, out); });
}

}  // namespace mesh_io_internal
}  // namespace confluent
