#pragma once
// Reading and writing meshes: OBJ (with MTL and texture) and PLY (ascii and binary little-endian).

#include <string>

#include "core/mesh.h"

namespace confluent {

// Options for writing a mesh.
struct MeshWriteOptions {
  bool binary = true;           // PLY only: binary little-endian instead of ascii
  bool write_colors = true;     // write per-vertex colours when the mesh has them
  bool write_face_labels = true;  // PLY only: a per-face int property "label"
  bool double_precision = false;  // PLY only: coordinates as double instead of float
};

// Reads an .obj or .ply file (chosen by extension, case-insensitive). Polygons are
// fan-triangulated. OBJ: reads `v` (with optional r g b), `vt`, `f` (all index forms,
// negative indices), `mtllib`/`map_Kd` (texture_path made absolute). PLY: ascii,
// binary_little_endian and binary_big_endian, vertex x y z [red green blue (uchar or float)]
// [u v], face vertex_indices, optional face "label" and "texcoord" list with
// "comment TextureFile" (MeshLab convention); unknown elements and properties are skipped.
// Colours are stored as read (uchar / 255), with no transfer function applied.
// Throws InputError naming the file on a missing file, bad syntax, out-of-range indices or
// non-finite coordinates.
Mesh ReadMesh(const std::string& path);

// Writes `mesh` as .obj or .ply by extension. OBJ writes an MTL next to it when the mesh has
// a texture (the texture itself is referenced, not copied). PLY writes uchar colours, face
// labels, and UVs as a per-face "texcoord" list with "comment TextureFile". Written
// atomically (temporary file, then rename). Throws OutputError on failure.
void WriteMesh(const std::string& path, const Mesh& mesh, const MeshWriteOptions& options = {});

}  // namespace confluent
