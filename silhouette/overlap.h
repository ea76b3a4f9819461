#pragma once
// Template-to-silhouette overlap without GL: the posed template's triangles are projected and
// filled (software rasterisation), then compared with the masks.

#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

// The silhouette of `mesh` in `camera` as a 1-channel 0/255 mask of size
// (camera.width / downscale) x (camera.height / downscale). Triangles with a vertex behind the
// camera are skipped. Distortion is respected per vertex.
Image RasterizeSilhouette(const Mesh& mesh, const Camera& camera, int downscale = 1);

// The silhouette of a closed (watertight) mesh in `camera` at full resolution, 0/255: the pixels
// whose centres lie inside a projected triangle that faces the camera. Faster than
// RasterizeSilhouette for dense meshes (a plain edge-function fill, half the triangles).
// Triangles with a vertex behind the camera are skipped; distortion is respected per vertex.
Image RasterizeClosedMesh(const Mesh& mesh, const Camera& camera);

// `mask` reduced by `downscale` (area average, thresholded at 50%), 0/255.
Image DownscaleMask(const Image& mask, int downscale);

// Per camera of `rig`, the IoU of the closed `mesh`'s silhouette with masks[c] (camera size, 0/255),
// both reduced by `downscale` (0: each camera to about 256 pixels across; the silhouette
// centre-sampled like the masks); -1 where use[c] is false or the mask is missing or of another size.
std::vector<double> SilhouetteIoUs(const Mesh& mesh, const Rig& rig, const std::vector<Image>& masks,
                                   const std::vector<bool>& use, int downscale = 0);

// The mean of the IoUs that SilhouetteIoUs computed (those >= 0); 0 when there are none.
double MeanSilhouetteIoU(const std::vector<double>& ious);

// Number of foreground (non-zero) pixels of a 1-channel 8-bit mask.
long CountForeground(const Image& mask);

// The image (converted to 8-bit RGB) with the outline of `rendered` (a 0/255 mask, e.g. from
// RasterizeSilhouette, resized to the image when smaller) drawn in red and, when `mask` is
// given, the outline of the mask drawn in green.
Image DrawSilhouetteOverlay(const Image& image, const Image& rendered, const Image* mask = nullptr);

}  // namespace confluent
