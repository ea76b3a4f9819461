#pragma once
// Splits a mesh with per-corner texture coordinates into one with per-vertex ones, as glTF
// (and GPUs) need: a scan vertex on a UV seam becomes one vertex per distinct UV.

#include <vector>

#include "core/mesh.h"

namespace confluent {

// A mesh whose vertices each carry one UV and remember the scan vertex they came from.
struct SeamSplitMesh {
  RowMatrixX3i faces;               // m x 3 indices into the split vertices, same order and
                                    // orientation as the scan's faces
  RowMatrixX2d uvs;                 // n x 2 texture coordinates (u right, v up), one per vertex
  std::vector<int> source_vertex;   // n: the scan vertex each split vertex copies

  int num_vertices() const { return static_cast<int>(source_vertex.size()); }
  int num_faces() const { return static_cast<int>(faces.rows()); }
  // The split vertices' positions taken from the scan's `scan_vertices` (scan count x 3).
  RowMatrixX3d Positions(const RowMatrixX3d& scan_vertices) const;
};

// Splits `mesh` at its UV seams: one split vertex per distinct (scan vertex, UV index) pair
// used by a face corner, numbered in order of first use. Vertices no face uses are dropped.
// Throws InputError("mesh") when the mesh has no per-corner UVs (Mesh::has_uvs) or an index
// is out of range.
SeamSplitMesh SplitAtUvSeams(const Mesh& mesh);

}  // namespace confluent
