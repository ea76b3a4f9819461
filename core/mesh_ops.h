#pragma once
// Small mesh utilities used everywhere: normals, areas, bounds, primitive generators and
// midpoint subdivision.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/mesh.h"

namespace confluent {

// Per-face cross product (b - a) x (c - a): direction is the CCW normal, length is twice the
// area. m x 3.
RowMatrixX3d FaceCrossProducts(const Mesh& mesh);

// Unit face normals (CCW seen from outside); zero rows for degenerate faces. m x 3.
RowMatrixX3d FaceNormals(const Mesh& mesh);

// Face areas in m^2 (length m).
Eigen::VectorXd FaceAreas(const Mesh& mesh);

// Area-weighted unit vertex normals; zero rows for vertices without (non-degenerate) faces. n x 3.
RowMatrixX3d VertexNormals(const Mesh& mesh);

// Axis-aligned bounding box of the vertices (empty box for a mesh without vertices).
Eigen::AlignedBox3d BoundingBox(const Mesh& mesh);

// Signed volume enclosed by a closed mesh in m^3 (positive when faces are CCW outward).
double SignedVolume(const Mesh& mesh);

// An axis-aligned box from `min_corner` to `max_corner`: 8 vertices, 12 triangles, watertight,
// CCW outward.
Mesh MakeBox(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner);

// A UV sphere centred at the origin with poles on the z axis: `rings` latitude bands (>= 2),
// `segments` longitude steps (>= 3). 2 + (rings-1)*segments vertices, watertight, CCW outward.
Mesh MakeUvSphere(double radius_m, int rings, int segments);

// A capsule centred at the origin along z: a cylinder of `length_m` (>= 0) between two
// hemispheres of `radius_m`; `rings` latitude bands per hemisphere (>= 1), `segments`
// longitude steps (>= 3). Watertight, CCW outward.
Mesh MakeCapsule(double radius_m, double length_m, int rings, int segments);

// Splits every triangle into 4 at its edge midpoints (no smoothing). Shared edges get one new
// vertex; colours and UVs are averaged, face labels copied to the 4 children.
Mesh SubdivideMidpoint(const Mesh& mesh);

}  // namespace confluent
