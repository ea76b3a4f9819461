#pragma once
// Silhouettes of a closed mesh from its rim alone. Over a closed surface seen from outside, the
// number of camera-facing triangles that cover a pixel changes only across rim edges (an edge
// between a facing and a turned-away triangle): across any other edge one facing triangle ends
// where its neighbour begins, or neither faces the camera. So the silhouette is the nonzero
// winding fill of the rim edges, each directed as in its facing triangle. Scan-converting a few
// thousand rim edges replaces filling every facing triangle of a dense scan (issue 23).

#include <array>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

// Rasterises silhouettes of one mesh topology in many poses and cameras.
class RimSilhouetteRasterizer {
 public:
  explicit RimSilhouetteRasterizer(const RowMatrixX3i& faces);

  // True when every edge joins exactly two triangles that run through it in opposite directions
  // (closed and consistently oriented): only then is the rim fill exact.
  bool closed() const { return closed_; }

  // The silhouette of the mesh with these `vertices` in `camera`, 0/255 at full resolution: the
  // pixels whose centres lie inside a projected triangle that faces the camera, as
  // RasterizeClosedMesh draws it (pixel centres exactly on a rim edge may differ). Falls back to
  // RasterizeClosedMesh when the topology is not closed or a vertex is behind the camera.
  Image Rasterize(const RowMatrixX3d& vertices, const Camera& camera) const;

 private:
  RowMatrixX3i faces_;
  // Each edge once, in the order of its first face: {from, to, the face that runs from -> to,
  // the face that runs to -> from}.
  std::vector<std::array<int, 4>> edges_;
  bool closed_ = false;
};

}  // namespace confluent
