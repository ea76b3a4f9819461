#include "export/gltf_reader.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <fstream>
#include <cstring>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "export/gltf_format.h"

namespace confluent {
namespace {

using nlohmann::json;
using namespace gltf;

class Decoder {
 public:
  Decoder(const std::vector<std::uint8_t>& glb, const std::string& name) : name_(name) {
    std::string text;
    UnpackGlb(glb, name, &text, &bin_);
    doc_ = json::parse(text, nullptr, false);
    if (doc_.is_discarded() || !doc_.is_object()) throw InputError(name, "the GLB's JSON chunk is not a JSON object");
  }

  const json& doc() const { return doc_; }

  // The bytes of a buffer view, decompressed when it uses EXT_meshopt_compression.
  std::vector<std::uint8_t> View(int index) {
    const json& view = At(doc_["bufferViews"], index, "bufferView");
    if (view.contains("extensions") && view["extensions"].contains(kMeshopt)) {
      const json& ext = view["extensions"][kMeshopt];
      const std::size_t count = ext.at("count"), stride = ext.at("byteStride");
      const std::size_t offset = ext.value("byteOffset", 0), length = ext.at("byteLength");
      if (ext.value("buffer", 0) != 0 || offset + length > bin_.size()) Fail("compressed bufferView out of range");
      if (ext.value("filter", "NONE") != "NONE") Fail("meshopt filters are not supported");
      std::vector<std::uint8_t> out(count * stride);
      const std::string mode = ext.at("mode");
      int status = -1;
      if (mode == "ATTRIBUTES") {
        status = meshopt_decodeVertexBuffer(out.data(), count, stride, bin_.data() + offset, length);
      } else if (mode == "TRIANGLES") {
        status = stride == 2 ? meshopt_decodeIndexBuffer(reinterpret_cast<std::uint16_t*>(out.data()), count,
                                                         bin_.data() + offset, length)
                             : meshopt_decodeIndexBuffer(reinterpret_cast<std::uint32_t*>(out.data()), count,
                                                         bin_.data() + offset, length);
      }
      if (status != 0) Fail("meshopt decoding failed (mode " + mode + ")");
      return out;
    }
    if (view.value("buffer", 0) != 0) Fail("a bufferView refers to a buffer other than the GLB's binary chunk");
    const std::size_t offset = view.value("byteOffset", 0), length = view.at("byteLength");
    if (offset + length > bin_.size()) Fail("bufferView out of range");
    return std::vector<std::uint8_t>(bin_.begin() + offset, bin_.begin() + offset + length);
  }

  // An accessor as doubles, `components` per element, normalised integers mapped to [-1, 1]
  // or [0, 1].
  std::vector<double> Accessor(int index) {
    const json& accessor = At(doc_["accessors"], index, "accessor");
    static const std::map<std::string, int> kComponents = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}};
    const auto type = kComponents.find(accessor.at("type").get<std::string>());
    if (type == kComponents.end()) Fail("unsupported accessor type");
    const int components = type->second;
    const std::size_t count = accessor.at("count");
    const int component_type = accessor.at("componentType");
    const bool normalized = accessor.value("normalized", false);
    const std::size_t size = component_type == kFloat || component_type == kUnsignedInt ? 4
                             : component_type == kShort || component_type == kUnsignedShort ? 2 : 1;
    const int view_index = accessor.at("bufferView");
    const std::vector<std::uint8_t> bytes = View(view_index);
    const json& view = doc_["bufferViews"][view_index];
    const std::size_t stride = view.value("byteStride", size * components);
    const std::size_t offset = accessor.value("byteOffset", 0);
    if (count > 0 && offset + (count - 1) * stride + size * components > bytes.size()) Fail("accessor out of range");
    std::vector<double> values(count * components);
    for (std::size_t i = 0; i < count; ++i) {
      for (int c = 0; c < components; ++c) {
        const std::uint8_t* p = bytes.data() + offset + i * stride + c * size;
        double value = 0.0;
        switch (component_type) {
          case kFloat: { float f; std::memcpy(&f, p, 4); value = f; break; }
          case kUnsignedInt: { std::uint32_t u; std::memcpy(&u, p, 4); value = u; break; }
          case kShort: { std::int16_t s; std::memcpy(&s, p, 2); value = normalized ? std::max(s / 32767.0, -1.0) : s; break; }
          case kUnsignedShort: { std::uint16_t u; std::memcpy(&u, p, 2); value = normalized ? u / 65535.0 : u; break; }
          case kByte: { const auto s = static_cast<std::int8_t>(*p); value = normalized ? std::max(s / 127.0, -1.0) : s; break; }
          case kUnsignedByte: value = normalized ? *p / 255.0 : *p; break;
          default: Fail("unsupported componentType " + std::to_string(component_type));
        }
        values[i * components + c] = value;
      }
    }
    return values;
  }

  [[noreturn]] void Fail(const std::string& problem) const { throw InputError(name_, problem); }

 private:
  const json& At(const json& array, int index, const char* what) const {
    if (!array.is_array() || index < 0 || index >= static_cast<int>(array.size())) {
      Fail(std::string(what) + " " + std::to_string(index) + " does not exist");
    }
    return array[index];
  }

  std::string name_;
  json doc_;
  std::vector<std::uint8_t> bin_;
};

Eigen::Vector3d Vec3(const json& node, const char* key, double fallback) {
  if (!node.contains(key)) return Eigen::Vector3d::Constant(fallback);
  return {node[key][0].get<double>(), node[key][1].get<double>(), node[key][2].get<double>()};
}

}  // namespace

Mesh GlbAnimation::FrameMesh(int frame) const {
  Mesh mesh;
  mesh.vertices = positions.at(frame);
  mesh.faces = faces;
  mesh.uvs = uvs;
  mesh.face_uvs = faces;
  return mesh;
}

GlbAnimation DecodeGlb(const std::vector<std::uint8_t>& glb, const std::string& name) {
  Decoder decoder(glb, name);
  const json& doc = decoder.doc();
  GlbAnimation out;
  try {
    out.extensions_required = doc.value("extensionsRequired", std::vector<std::string>{});
    const json& scene = doc.at("scenes").at(doc.value("scene", 0));
    out.fps = scene.at("extras").at("fps");
    const json& root = doc.at("nodes").at(scene.at("nodes").at(0).get<int>());
    if (root.value("name", "") != kRootName) decoder.Fail("the scene's root node is not '" + std::string(kRootName) + "'");
    const json& scan = doc.at("nodes").at(root.at("children").at(0).get<int>());
    if (scan.contains("rotation") || scan.contains("matrix")) decoder.Fail("the scan node must have only translation and scale");
    const Eigen::Vector3d translation = Vec3(scan, "translation", 0.0), scale = Vec3(scan, "scale", 1.0);
    for (const json& child : scan.at("children")) {
      const json& node = doc.at("nodes").at(child.get<int>());
      const json& primitive = doc.at("meshes").at(node.at("mesh").get<int>()).at("primitives").at(0);
      const json& attributes = primitive.at("attributes");
      if (out.positions.empty()) {
        const std::vector<double> indices = decoder.Accessor(primitive.at("indices"));
        out.faces.resize(static_cast<Eigen::Index>(indices.size() / 3), 3);
        for (std::size_t i = 0; i < indices.size(); ++i) out.faces(i / 3, i % 3) = static_cast<int>(indices[i]);
        const std::vector<double> uv = decoder.Accessor(attributes.at("TEXCOORD_0"));
        out.uvs.resize(static_cast<Eigen::Index>(uv.size() / 2), 2);
        for (std::size_t i = 0; i < uv.size() / 2; ++i) out.uvs.row(i) << uv[2 * i], 1.0 - uv[2 * i + 1];
        if (scene["extras"].contains("source_vertex_accessor")) {
          for (double v : decoder.Accessor(scene["extras"]["source_vertex_accessor"])) {
            out.source_vertex.push_back(static_cast<int>(v));
          }
        }
      }
      const std::vector<double> p = decoder.Accessor(attributes.at("POSITION"));
      const std::vector<double> m = decoder.Accessor(attributes.at("NORMAL"));
      const Eigen::Index n = static_cast<Eigen::Index>(p.size() / 3);
      if (n != out.uvs.rows() || m.size() != p.size()) decoder.Fail("frame " + std::to_string(out.positions.size()) + " has a different vertex count");
      RowMatrixX3d positions(n, 3), normals(n, 3);
      for (Eigen::Index i = 0; i < n; ++i) {
        positions.row(i) = (translation.array() + scale.array() * Eigen::Array3d(p[3 * i], p[3 * i + 1], p[3 * i + 2])).matrix().transpose();
        normals.row(i) = Eigen::Vector3d(m[3 * i], m[3 * i + 1], m[3 * i + 2]).normalized().transpose();
      }
      out.positions.push_back(std::move(positions));
      out.normals.push_back(std::move(normals));
    }
    const json& image = doc.at("images").at(0);
    out.image = decoder.View(image.at("bufferView"));
    out.image_mime_type = image.value("mimeType", "");
  } catch (const json::exception& error) {
    decoder.Fail(std::string("not a confluent glTF layout: ") + error.what());
  }
  if (out.positions.empty()) decoder.Fail("no frame nodes under the scan node");
  if (out.faces.size() > 0 && (out.faces.minCoeff() < 0 || out.faces.maxCoeff() >= out.uvs.rows())) {
    decoder.Fail("a triangle index is out of range");
  }
  if (!out.source_vertex.empty() && static_cast<Eigen::Index>(out.source_vertex.size()) != out.uvs.rows()) {
    decoder.Fail("the source vertex accessor's count differs from the vertex count");
  }
  return out;
}

GlbAnimation ReadGlb(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path, "cannot be opened");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  return DecodeGlb(bytes, path);
}

}  // namespace confluent
