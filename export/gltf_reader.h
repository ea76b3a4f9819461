#pragma once
// Reads back a scene.glb written by export/gltf_writer.h (frame nodes under the "scan" node),
// decoding KHR_mesh_quantization and EXT_meshopt_compression: for round-trip tests and for
// rendering an export with confluent's own renderer.

#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace confluent {

struct GlbAnimation {
  RowMatrixX3i faces;                   // m x 3 indices into the (seam-split) vertices
  RowMatrixX2d uvs;                     // n x 2, u right, v up (core/mesh.h convention)
  std::vector<int> source_vertex;       // n: the scan vertex of each vertex (the scene's extras.source_vertex_accessor)
  // Per frame, n x 3, in confluent's world frame (Z up): the scan node's transform is applied,
  // the root node's fixed Z-up-to-Y-up rotation is not.
  std::vector<RowMatrixX3d> positions;
  std::vector<RowMatrixX3d> normals;    // per frame, n x 3 unit normals, same frame
  double fps = 0.0;                     // the scene's extras.fps
  std::vector<std::uint8_t> image;      // the base colour image's encoded bytes
  std::string image_mime_type;          // "image/jpeg" or "image/png"
  std::vector<std::string> extensions_required;

  // The frame as a Mesh with per-corner UVs (face_uvs = faces).
  Mesh FrameMesh(int frame) const;
};

// Decodes GLB bytes; `name` names the file in errors. Throws InputError(name) when the bytes
// are not a GLB of this layout or an accessor or buffer view is out of range.
GlbAnimation DecodeGlb(const std::vector<std::uint8_t>& glb, const std::string& name = "scene.glb");

// Reads and decodes the file at `path`. Throws InputError(path).
GlbAnimation ReadGlb(const std::string& path);

}  // namespace confluent
