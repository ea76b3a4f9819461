#pragma once
// Triangle mesh with optional per-vertex colours and per-corner texture coordinates.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace confluent {

using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixX3i = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixX3f = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatrixX2d = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;

// A triangle mesh. Units are metres in the world frame unless stated otherwise.
struct Mesh {
  RowMatrixX3d vertices;        // n x 3 positions
  RowMatrixX3i faces;           // m x 3 vertex indices, counter-clockwise seen from outside
  RowMatrixX3f colors;          // n x 3 RGB in [0,1] as stored in the file (uchar / 255), or empty
  RowMatrixX2d uvs;             // k x 2 texture coordinates (u right, v up), or empty
  RowMatrixX3i face_uvs;        // m x 3 indices into `uvs`, or empty
  std::string texture_path;     // absolute path of the diffuse texture image, or empty
  std::vector<int> face_labels; // m per-face labels (e.g. body segment id), or empty

  int num_vertices() const { return static_cast<int>(vertices.rows()); }
  int num_faces() const { return static_cast<int>(faces.rows()); }
  bool has_colors() const { return colors.rows() == vertices.rows() && colors.rows() > 0; }
  bool has_uvs() const { return uvs.rows() > 0 && face_uvs.rows() == faces.rows(); }
  bool has_face_labels() const { return static_cast<int>(face_labels.size()) == num_faces() && num_faces() > 0; }
};

}  // namespace confluent
