#pragma once
// Decimation of a seam-split mesh (export/seam_split.h) for the streamable glTF variant, with
// meshoptimizer's simplifier (Garland and Heckbert 1997 quadrics; edge collapses onto existing
// vertices). Kept vertices are original vertices, so they keep their UV and scan vertex and
// animate from the full mesh's per-frame positions.

#include "core/mesh.h"
#include "export/seam_split.h"

namespace confluent {

struct DecimateOptions {
  int target_triangles = 10000;  // triangle count to reach (>= 1); borders may keep it above
  // Largest geometric error allowed, relative to the mesh's extent (meshoptimizer's
  // target_error); 1 lets the triangle count alone decide.
  double max_relative_error = 1.0;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

struct DecimateSummary {
  int input_triangles = 0;
  int output_triangles = 0;
  int output_vertices = 0;
  double relative_error = 0.0;  // meshoptimizer's resulting error, relative to the extent
};

// Decimates `mesh` (positions from `scan_vertices`, the scan's vertices in the pose to simplify
// in, e.g. frame 0) towards options.target_triangles. Mesh borders and the UV seams are locked:
// the atlas's charts keep their outlines. The
// result keeps only the vertices its faces use, in order of first use. A mesh already at or
// below the target comes back unchanged. Throws UsageError for bad options and InputError
// ("mesh") when `scan_vertices` has too few rows for the mesh's source vertices.
SeamSplitMesh DecimateSplitMesh(const SeamSplitMesh& mesh, const RowMatrixX3d& scan_vertices,
                                const DecimateOptions& options, DecimateSummary* summary = nullptr);

}  // namespace confluent
