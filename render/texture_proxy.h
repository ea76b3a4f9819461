#pragma once
// The coarse proxy mesh that projective texturing (render/projective_texture.h) draws the
// visibility depth maps from. Internal to render/.

#include "core/mesh.h"

namespace confluent::render_internal {

// A coarse proxy of `mesh` for the visibility depth maps, by vertex clustering on a grid: every
// cluster is represented by one of its own vertices (the one nearest the cluster's mean), so the
// proxy's faces index the mesh's vertices and follow them when they move. Faces that collapse are
// dropped, and so are duplicates. The cell size is chosen for about `target_faces` faces; returns
// the faces and, in *deviation_m, the largest distance of a vertex from its representative along
// the vertex normal (how far the proxy's surface can lie in front of the mesh).
RowMatrixX3i ProxyFaces(const Mesh& mesh, int target_faces, double* deviation_m);

}  // namespace confluent::render_internal
