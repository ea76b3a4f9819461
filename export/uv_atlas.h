#pragma once
// The scan's UV atlas, computed once per run (its topology is fixed for the whole capture):
// charts that follow the body, each flattened with least-squares conformal maps (Levy et al.
// 2002, "Least Squares Conformal Maps for Automatic Texture Atlas Generation"), packed into a
// square atlas with gutters, at one texel density for the whole mesh.
//
// Charts. Faces are grouped by segment label (Mesh::face_labels, when present) and by the
// dominant axis of their normal (+-x, +-y, +-z, smoothed over neighbours so that chart outlines
// are not ragged), then split into edge-connected components; components smaller than
// min_chart_faces join the neighbour they share most edges with. A chart that is not a disc
// (Euler characteristic != 1: closed, with holes or handles), whose flattening flips or overlaps
// a triangle, whose stretch exceeds max_chart_stretch, or that fills less than min_chart_fill of
// its bounding box is cut in two across its longest
// principal axis (at the area median) and each part is tried again, down to single triangles.
//
// Packing. Each chart is rotated to its principal axes (long side horizontal) and scaled so that
// its UV area equals its surface area; the charts are skyline-packed (bottom-left, upright or
// turned by 90 degrees), tallest first, each inside padding_px texels of its own gutter (charts
// are at least 2 padding_px apart); the texel density
// is the largest that fits (binary search).

#include <Eigen/Core>

#include "core/mesh.h"

namespace confluent {

// Options of BuildUvAtlas.
struct UvAtlasOptions {
  int size_px = 2048;    // atlas width and height, texels (64..16384)
  int padding_px = 4;    // gutter around each chart, texels (0..64)
  // Largest area-weighted L2 stretch (Sander et al. 2001) a chart may have before it is cut, >= 1.
  double max_chart_stretch = 1.25;
  // A chart of 256 faces or more whose area fills less of its bounding box (in its principal axes)
  // is cut: ragged charts waste atlas texels (0 = never).
  double min_chart_fill = 0.3;
  // Connected pieces with fewer faces join a neighbouring chart (0 = keep every piece).
  int min_chart_faces = 24;
  // Passes of the majority filter that smooths the normal-direction grouping (0 = none).
  int smoothing_passes = 4;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// Quality figures of an atlas.
struct UvAtlasStats {
  int charts = 0;
  // Fraction of the atlas texels whose centre lies inside a UV triangle.
  double texel_use = 0;
  // Stretch of the parameterisation, Sander et al. 2001 ("Texture Mapping Progressive Meshes"):
  // per triangle L2 = sqrt((a + c) / 2), with a, c the squared lengths of the surface's
  // derivatives along u and v, the atlas scaled so that the total UV area equals the total
  // surface area (a uniform texel density has L2 = 1 everywhere; 1 = no stretch).
  // stretch_mean: the surface-area-weighted RMS of L2 over all triangles (Sander's L2 norm of the
  // whole atlas); stretch_max: the largest per-triangle L2 (triangles of zero area excluded).
  double stretch_mean = 0;
  double stretch_max = 0;
};

// A mesh's UV atlas: per-corner texture coordinates in the layout of core/mesh.h (u right, v up,
// in [0, 1]; the atlas image's top row is v = 1).
struct UvAtlas {
  RowMatrixX2d uvs;        // k x 2 texture coordinates (one per chart vertex)
  RowMatrixX3i face_uvs;   // m x 3 indices into uvs, per face corner
  int size_px = 0;         // the atlas resolution the layout was packed for
  UvAtlasStats stats;
};

// Builds the atlas of `mesh` (face labels used when present). Every face gets UVs in [0, 1],
// counter-clockwise (not flipped) and overlapping no other face. Throws InputError("mesh") for a
// mesh without faces, with out-of-range indices or non-finite vertices, UsageError for bad
// options, and InputError when the charts do not fit the atlas at one texel per chart.
UvAtlas BuildUvAtlas(const Mesh& mesh, const UvAtlasOptions& options = {});

// The mesh with the atlas's UVs (uvs, face_uvs) set, ready for MeshRenderer::AddMesh with the
// baked texture. Throws InputError when the atlas does not match the mesh's face count.
Mesh WithAtlasUvs(const Mesh& mesh, const UvAtlas& atlas);

}  // namespace confluent
