#pragma once
// Ground-truth masks for tracking tests: the template's own silhouettes in a known pose.

#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "silhouette/overlap.h"
#include "tracking/body_template.h"

namespace confluent::testing {

// The template's silhouettes in `pose`, one per camera of `rig` (centre-sampled).
inline std::vector<Image> TemplateMasks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose,
                                        const Rig& rig) {
  const Mesh mesh = body.PosedMesh(shape, pose);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(mesh, camera));
  return masks;
}

}  // namespace confluent::testing
