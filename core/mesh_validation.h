#pragma once
// Mesh validation report: topology and degeneracy checks.

#include <string>
#include <vector>

#include "core/mesh.h"

namespace confluent {

// Options for ValidateMesh.
struct MeshValidationOptions {
  double degenerate_area_m2 = 1e-14;  // faces with area below this count as degenerate
};

// What ValidateMesh found. Index lists are 0-based.
struct MeshReport {
  int num_vertices = 0;
  int num_faces = 0;
  std::vector<std::pair<int, int>> non_manifold_edges;  // edges shared by > 2 faces
  std::vector<int> non_manifold_vertices;  // vertices whose one-ring is not a single fan
  std::vector<int> degenerate_faces;       // zero area or repeated vertex index
  std::vector<int> duplicate_faces;        // same vertex set as an earlier face
  std::vector<int> unreferenced_vertices;  // used by no face
  std::vector<int> invalid_vertices;       // non-finite coordinates
  int num_components = 0;                  // connected components (by shared vertices)
  std::vector<int> component_of_face;      // m component ids
  int num_boundary_loops = 0;              // closed loops of boundary edges
  int num_boundary_edges = 0;

  bool is_manifold() const { return non_manifold_edges.empty() && non_manifold_vertices.empty(); }
  bool is_watertight() const { return is_manifold() && num_boundary_edges == 0; }
  bool is_clean() const {
    return is_manifold() && degenerate_faces.empty() && duplicate_faces.empty() &&
           invalid_vertices.empty();
  }
  // A multi-line human-readable summary.
  std::string ToString() const;
};

// Checks `mesh` and returns the report; never throws for bad geometry.
MeshReport ValidateMesh(const Mesh& mesh, const MeshValidationOptions& options = {});

}  // namespace confluent
