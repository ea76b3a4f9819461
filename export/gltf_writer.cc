#include "export/gltf_writer.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mesh_ops.h"
#include "export/gltf_format.h"
#include "export/mesh_decimate.h"
#include "export/seam_split.h"

namespace confluent {
namespace {

using nlohmann::json;
using namespace gltf;

// Accumulates the binary chunk, buffer views and accessors of one GLB. Views made with
// AddStream are compressed with meshoptimizer when `compress` is set: their data then lives in
// the binary chunk (buffer 0) and the view itself points into an unbacked fallback buffer.
class GlbBuilder {
 public:
  explicit GlbBuilder(bool compress) : compress_(compress) {}

  // A plain view of `bytes` in the binary chunk (4-byte aligned).
  int AddView(const void* data, std::size_t bytes, int stride = 0, int target = 0) {
    const std::size_t offset = Append(data, bytes);
    json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
    if (stride) view["byteStride"] = stride;
    if (target) view["target"] = target;
    views_.push_back(view);
    return static_cast<int>(views_.size()) - 1;
  }

  // A vertex stream (`count` elements of `stride` bytes, stride % 4 == 0) or, with
  // `indices`, an index stream (`count` uint16/uint32 indices, stride 2 or 4).
  // `vertex_data` = false leaves the view without a GPU target (data for readers only).
  int AddStream(const void* data, std::size_t count, int stride, bool indices, bool vertex_data = true) {
    const int target = indices ? kElementArrayBuffer : vertex_data ? kArrayBuffer : 0;
    if (!compress_) return AddView(data, count * stride, target == kArrayBuffer ? stride : 0, target);
    std::vector<unsigned char> encoded;
    if (indices) {
      std::vector<unsigned int> wide(count);
      for (std::size_t i = 0; i < count; ++i) {
        wide[i] = stride == 2 ? static_cast<const std::uint16_t*>(data)[i] : static_cast<const std::uint32_t*>(data)[i];
      }
      std::size_t max_vertex = 0;
      for (unsigned int v : wide) max_vertex = std::max<std::size_t>(max_vertex, v);
      encoded.resize(meshopt_encodeIndexBufferBound(count, max_vertex + 1));
      encoded.resize(meshopt_encodeIndexBuffer(encoded.data(), encoded.size(), wide.data(), count));
    } else {
      encoded.resize(meshopt_encodeVertexBufferBound(count, stride));
      encoded.resize(meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), data, count, stride));
    }
    const std::size_t offset = Append(encoded.data(), encoded.size());
    const std::size_t bytes = count * stride;
    fallback_bytes_ = Align4(fallback_bytes_);
    json view = {{"buffer", 1}, {"byteOffset", fallback_bytes_}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    if (target == kArrayBuffer) view["byteStride"] = stride;
    view["extensions"][kMeshopt] = {{"buffer", 0},          {"byteOffset", offset},
                                    {"byteLength", encoded.size()}, {"byteStride", stride},
                                    {"count", count},       {"mode", indices ? "TRIANGLES" : "ATTRIBUTES"}};
    fallback_bytes_ += bytes;
    views_.push_back(view);
    return static_cast<int>(views_.size()) - 1;
  }

  int AddAccessor(int view, int component_type, std::size_t count, const char* type, bool normalized,
                  const json& min = nullptr, const json& max = nullptr) {
    json accessor = {{"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}};
    if (normalized) accessor["normalized"] = true;
    if (!min.is_null()) accessor["min"] = min;
    if (!max.is_null()) accessor["max"] = max;
    accessors_.push_back(accessor);
    return static_cast<int>(accessors_.size()) - 1;
  }

  // Floats as a plain view plus accessor (animation data), with min/max.
  int AddFloats(const std::vector<float>& values, int components, const char* type) {
    const int view = AddView(values.data(), values.size() * sizeof(float));
    json min = json::array(), max = json::array();
    for (int c = 0; c < components; ++c) {
      float lo = values[c], hi = values[c];
      for (std::size_t i = c; i < values.size(); i += components) lo = std::min(lo, values[i]), hi = std::max(hi, values[i]);
      min.push_back(lo);
      max.push_back(hi);
    }
    return AddAccessor(view, kFloat, values.size() / components, type, false, min, max);
  }

  // Fills the document's buffers, bufferViews and accessors and returns the GLB bytes.
  std::vector<std::uint8_t> Finish(json document) {
    json buffers = json::array({{{"byteLength", bin_.size()}}});
    if (compress_) buffers.push_back({{"byteLength", std::max<std::size_t>(fallback_bytes_, 4)},
                                      {"extensions", {{kMeshopt, {{"fallback", true}}}}}});
    document["buffers"] = buffers;
    document["bufferViews"] = views_;
    document["accessors"] = accessors_;
    return PackGlb(document.dump(), bin_);
  }

 private:
  static std::size_t Align4(std::size_t n) { return (n + 3) & ~std::size_t{3}; }
  std::size_t Append(const void* data, std::size_t bytes) {
    bin_.resize(Align4(bin_.size()), 0);
    const std::size_t offset = bin_.size();
    const auto* begin = static_cast<const std::uint8_t*>(data);
    bin_.insert(bin_.end(), begin, begin + bytes);
    return offset;
  }

  bool compress_;
  std::vector<std::uint8_t> bin_;
  std::size_t fallback_bytes_ = 0;
  json views_ = json::array();
  json accessors_ = json::array();
};

void CheckInputs(const Mesh& scan, const std::vector<RowMatrixX3d>& frames, const Image& base_color) {
  if (frames.empty()) throw InputError("frames", "no frame to export");
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (frames[k].rows() != scan.num_vertices()) {
      throw InputError("frames", "frame " + std::to_string(k) + " has " + std::to_string(frames[k].rows()) +
                                     " vertices, the scan " + std::to_string(scan.num_vertices()));
    }
    if (!frames[k].allFinite()) throw InputError("frames", "frame " + std::to_string(k) + " has a non-finite vertex");
  }
  if (base_color.empty() || base_color.type != PixelType::kUInt8 || (base_color.channels != 3 && base_color.channels != 4)) {
    throw InputError("base colour", "must be a non-empty 8-bit RGB or RGBA image");
  }
}

std::vector<std::uint8_t> EncodeTexture(const Image& image, const GltfOptions& options) {
  cv::Mat rgb(image.height, image.width, image.channels == 3 ? CV_8UC3 : CV_8UC4,
              const_cast<std::uint8_t*>(image.data.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, image.channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGR);
  std::vector<std::uint8_t> bytes;
  const bool ok = options.jpeg_texture
                      ? cv::imencode(".jpg", bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality})
                      : cv::imencode(".png", bgr, bytes);
  if (!ok) throw InputError("base colour", "could not be encoded");
  return bytes;
}

// The split vertices reordered for the GPU's vertex cache and for meshoptimizer's codecs.
void OptimizeOrder(SeamSplitMesh* mesh) {
  const std::size_t n = mesh->num_vertices();
  std::vector<unsigned int> indices(mesh->faces.data(), mesh->faces.data() + mesh->faces.size());
  meshopt_optimizeVertexCache(indices.data(), indices.data(), indices.size(), n);
  std::vector<unsigned int> remap(n);
  const std::size_t used = meshopt_optimizeVertexFetchRemap(remap.data(), indices.data(), indices.size(), n);
  SeamSplitMesh out;
  out.faces.resize(mesh->faces.rows(), 3);
  for (std::size_t i = 0; i < indices.size(); ++i) out.faces(i / 3, i % 3) = static_cast<int>(remap[indices[i]]);
  out.source_vertex.assign(used, 0);
  out.uvs.resize(static_cast<Eigen::Index>(used), 2);
  for (std::size_t v = 0; v < n; ++v) {
    if (remap[v] == ~0u) continue;
    out.source_vertex[remap[v]] = mesh->source_vertex[v];
    out.uvs.row(remap[v]) = mesh->uvs.row(v);
  }
  *mesh = std::move(out);
}

// Min (or max) of the quantised x, y, z over the vertices (xyzw), for the accessor bounds.
json Bounds(const std::vector<std::int16_t>& xyzw, bool max) {
  json bounds = json::array();
  for (int c = 0; c < 3; ++c) {
    int value = max ? -32768 : 32767;
    for (std::size_t i = c; i < xyzw.size(); i += 4) value = max ? std::max<int>(value, xyzw[i]) : std::min<int>(value, xyzw[i]);
    bounds.push_back(value);
  }
  return bounds;
}

}  // namespace

void GltfOptions::Check() const {
  RequireOption(std::isfinite(fps) && fps > 0.0, "GltfOptions.fps", fps, "> 0");
  RequireOption(std::isfinite(position_step_m) && position_step_m > 0.0, "GltfOptions.position_step_m",
                position_step_m, "> 0");
  RequireOption(decimate_triangles >= 0, "GltfOptions.decimate_triangles", decimate_triangles, ">= 0");
  RequireOption(jpeg_quality >= 1 && jpeg_quality <= 100, "GltfOptions.jpeg_quality", jpeg_quality, "in 1..100");
}

std::vector<std::uint8_t> EncodeGlb(const Mesh& scan, const std::vector<RowMatrixX3d>& frames,
                                    const Image& base_color, const GltfOptions& options, GltfSummary* summary) {
  options.Check();
  if (!scan.has_uvs()) throw InputError("scan", "has no per-corner texture coordinates (UVs)");
  CheckInputs(scan, frames, base_color);
  GltfSummary result;
  result.frames = static_cast<int>(frames.size());

  SeamSplitMesh split = SplitAtUvSeams(scan);
  if (options.decimate_triangles > 0) {
    DecimateOptions decimate;
    decimate.target_triangles = options.decimate_triangles;
    DecimateSummary decimated;
    split = DecimateSplitMesh(split, frames[0], decimate, &decimated);
    result.decimation_error = decimated.relative_error;
  }
  OptimizeOrder(&split);
  const std::size_t n = split.num_vertices();
  result.vertices = static_cast<int>(n);
  result.triangles = split.num_faces();
  if (n == 0) throw InputError("scan", "has no faces to export");

  // One quantisation for all frames: integer steps from the centre of the bounding box of the
  // frames' used vertices, uniform so that the node scale keeps normals undistorted; coarser
  // than asked only when int16 cannot span the box.
  Eigen::AlignedBox3d box;
  for (const RowMatrixX3d& frame : frames) {
    for (int v : split.source_vertex) box.extend(frame.row(v).transpose());
  }
  const Eigen::Vector3d center = box.center();
  const double step = std::max({options.position_step_m, 0.5 * box.sizes().maxCoeff() / 32767.0, 1e-12});
  result.position_step_m = step;

  const bool compress = options.meshopt_compression;
  if (compress) {
    meshopt_encodeVertexVersion(0);  // the versions EXT_meshopt_compression specifies
    meshopt_encodeIndexVersion(1);
  }
  GlbBuilder builder(compress);

  // Shared indices and UVs.
  const bool wide = n > 65535;
  int index_accessor;
  {
    const std::size_t count = split.faces.size();
    int view;
    if (wide) {
      std::vector<std::uint32_t> indices(split.faces.data(), split.faces.data() + count);
      view = builder.AddStream(indices.data(), count, 4, true);
    } else {
      std::vector<std::uint16_t> indices(split.faces.data(), split.faces.data() + count);
      view = builder.AddStream(indices.data(), count, 2, true);
    }
    index_accessor = builder.AddAccessor(view, wide ? kUnsignedInt : kUnsignedShort, count, "SCALAR", false);
  }
  int uv_accessor;
  const bool uvs_in_unit_square = (split.uvs.array() >= 0.0).all() && (split.uvs.array() <= 1.0).all();
  if (uvs_in_unit_square) {
    std::vector<std::uint16_t> uv(2 * n);
    for (std::size_t i = 0; i < n; ++i) {
      uv[2 * i] = static_cast<std::uint16_t>(std::lround(split.uvs(i, 0) * 65535.0));
      uv[2 * i + 1] = static_cast<std::uint16_t>(std::lround((1.0 - split.uvs(i, 1)) * 65535.0));  // glTF: v down
    }
    uv_accessor = builder.AddAccessor(builder.AddStream(uv.data(), n, 4, false), kUnsignedShort, n, "VEC2", true);
  } else {
    std::vector<float> uv(2 * n);
    for (std::size_t i = 0; i < n; ++i) {
      uv[2 * i] = static_cast<float>(split.uvs(i, 0));
      uv[2 * i + 1] = static_cast<float>(1.0 - split.uvs(i, 1));
    }
    uv_accessor = builder.AddAccessor(builder.AddStream(uv.data(), n, 8, false), kFloat, n, "VEC2", false);
  }

  // The scan vertex of every split vertex, so that readers can map the export back to the scan.
  const std::vector<std::uint32_t> source(split.source_vertex.begin(), split.source_vertex.end());
  const int source_accessor =
      builder.AddAccessor(builder.AddStream(source.data(), n, 4, false, false), kUnsignedInt, n, "SCALAR", false);

  // Per frame: quantised positions and normals (smooth across seams: from the scan's topology);
  // without per-frame normals, every frame shares frame 0's.
  json meshes = json::array();
  json nodes = json::array();
  json frame_nodes = json::array();
  Mesh topology;
  topology.faces = scan.faces;
  int normal_accessor = -1;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    std::vector<std::int16_t> position(4 * n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d q = (frames[k].row(split.source_vertex[i]).transpose() - center) / step;
      for (int c = 0; c < 3; ++c) {
        position[4 * i + c] = static_cast<std::int16_t>(std::clamp<long>(std::lround(q[c]), -32767, 32767));
      }
    }
    const int position_accessor = builder.AddAccessor(builder.AddStream(position.data(), n, 8, false), kShort, n,
                                                      "VEC3", false, Bounds(position, false), Bounds(position, true));
    if (k == 0 || options.per_frame_normals) {
      topology.vertices = frames[k];
      const RowMatrixX3d normals = VertexNormals(topology);
      std::vector<std::int8_t> normal(4 * n, 0);
      for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector3d m = normals.row(split.source_vertex[i]).transpose();
        if (!(m.norm() > 0.5)) m = Eigen::Vector3d::UnitZ();  // a vertex of degenerate faces only
        m.normalize();
        for (int c = 0; c < 3; ++c) {
          normal[4 * i + c] = static_cast<std::int8_t>(std::clamp<long>(std::lround(m[c] * 127.0), -127, 127));
        }
      }
      normal_accessor = builder.AddAccessor(builder.AddStream(normal.data(), n, 4, false), kByte, n, "VEC3", true);
    }
    json primitive = {{"attributes", {{"POSITION", position_accessor}, {"NORMAL", normal_accessor}, {"TEXCOORD_0", uv_accessor}}},
                      {"indices", index_accessor},
                      {"material", 0},
                      {"mode", 4}};
    meshes.push_back({{"name", FrameName(static_cast<int>(k))}, {"primitives", json::array({primitive})}});
    json node = {{"name", FrameName(static_cast<int>(k))}, {"mesh", k}};
    if (k > 0) node["scale"] = {0.0, 0.0, 0.0};
    nodes.push_back(node);
    frame_nodes.push_back(k + 2);
  }
  // Node 0 turns confluent's Z-up world into glTF's Y-up one, node 1 is the scan (undoing the
  // position quantisation); the frame nodes follow.
  const double half_sqrt2 = std::sqrt(0.5);
  json root_node = {{"name", kRootName}, {"rotation", {-half_sqrt2, 0.0, 0.0, half_sqrt2}}, {"children", {1}}};
  json scan_node = {{"name", "scan"},
                    {"translation", {center.x(), center.y(), center.z()}},
                    {"scale", {step, step, step}},
                    {"children", frame_nodes}};
  nodes.insert(nodes.begin(), {root_node, scan_node});

  // The animation: each frame node's scale, STEP-keyed.
  json samplers = json::array(), channels = json::array();
  const int num_frames = static_cast<int>(frames.size());
  const auto time = [&](int k) { return static_cast<float>(k / options.fps); };
  for (int k = 0; k < num_frames; ++k) {
    std::vector<float> times, scales;
    const auto key = [&](float t, float s) {
      times.push_back(t);
      scales.insert(scales.end(), {s, s, s});
    };
    if (k == 0) {
      key(0.0f, 1.0f);
      key(time(1), num_frames == 1 ? 1.0f : 0.0f);
    } else {
      key(0.0f, 0.0f);
      key(time(k), 1.0f);
      key(time(k + 1), k + 1 == num_frames ? 1.0f : 0.0f);
    }
    samplers.push_back({{"input", builder.AddFloats(times, 1, "SCALAR")},
                        {"output", builder.AddFloats(scales, 3, "VEC3")},
                        {"interpolation", "STEP"}});
    channels.push_back({{"sampler", k}, {"target", {{"node", k + 2}, {"path", "scale"}}}});
  }

  const std::vector<std::uint8_t> texture = EncodeTexture(base_color, options);
  const int image_view = builder.AddView(texture.data(), texture.size());

  json document;
  document["asset"] = {{"version", "2.0"}, {"generator", options.generator}};
  json used = {kQuantization, kUnlit};
  json required = {kQuantization};
  if (compress) {
    used.push_back(kMeshopt);
    required.push_back(kMeshopt);
  }
  document["extensionsUsed"] = used;
  document["extensionsRequired"] = required;
  document["scene"] = 0;
  document["scenes"] = {{{"name", "confluent"}, {"nodes", {0}},
                         {"extras", {{"fps", options.fps}, {"frames", num_frames}, {"source_vertex_accessor", source_accessor}}}}};
  document["nodes"] = nodes;
  document["meshes"] = meshes;
  document["materials"] = {{{"name", "atlas"},
                            {"pbrMetallicRoughness",
                             {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}},
                            {"doubleSided", true},
                            {"extensions", {{kUnlit, json::object()}}}}};
  document["textures"] = {{{"sampler", 0}, {"source", 0}}};
  document["samplers"] = {{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 33071}}};
  document["images"] = {{{"bufferView", image_view}, {"mimeType", options.jpeg_texture ? "image/jpeg" : "image/png"}}};
  document["animations"] = {{{"name", "frames"}, {"samplers", samplers}, {"channels", channels}}};

  std::vector<std::uint8_t> glb = builder.Finish(std::move(document));
  result.bytes = glb.size();
  if (summary) *summary = result;
  return glb;
}

GltfSummary WriteGlb(const std::string& path, const Mesh& scan, const std::vector<RowMatrixX3d>& frames,
                     const Image& base_color, const GltfOptions& options) {
  GltfSummary summary;
  const std::vector<std::uint8_t> glb = EncodeGlb(scan, frames, base_color, options, &summary);
  WriteAtomically(path, [&](const std::string& temporary) { WriteFileBytes(temporary, glb.data(), glb.size()); });
  return summary;
}

}  // namespace confluent
