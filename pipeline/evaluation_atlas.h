#pragma once
// The atlas-textured scan of the held-out evaluation (`confluent evaluate --texture atlas`): the
// run's scan gets a UV atlas (export/uv_atlas.h); each scored frame is baked from the cameras the
// run used (export/atlas_bake.h, the same images, masks and texturing as the projective path)
// into one atlas per held-out camera (the input colours matched to that camera when the
// evaluation matches colours), the atlases go through an H.264 round trip (core/video_writer.h,
// then core/video.h) so that the figures include the video compression of an export, and the
// animated scan is rendered with the decoded atlas by MeshRenderer (unlit; the output equals the
// texture) into the held-out cameras.

#include <memory>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/video_writer.h"
#include "export/uv_atlas.h"
#include "render/projective_texture.h"
#include "render/renderer.h"

namespace confluent {

// Options of AtlasTexturedScan.
struct AtlasTexturingOptions {
  int atlas_size_px = 2048;       // atlas width and height
  VideoWriterOptions video;       // the H.264 round trip (fps: the run's)
  // Colour samples per pixel and axis (1..4): the colour is the mean of the covered samples of an
  // n x n grid (the silhouette stays the pixel centres', as in the projective path). MeshRenderer
  // samples textures trilinearly from mip-maps chosen by the larger screen derivative: at one
  // sample per pixel that blurs over about twice a pixel's footprint, where the projective path
  // samples the input images at points; n x n samples take the blur down to about the pixel's
  // own, as a player's anisotropic filtering or multisampling would. Demo run, 25 frames, 2048
  // atlas: native 28.85 dB; atlas 27.72 dB at 4 x 4, 27.23 at 2 x 2, 25.79 at 1 x 1.
  int supersampling = 4;
  ProjectiveTextureOptions texturing;  // the baking's blending (as the projective path)
  void Check() const;             // throws UsageError
};

// Bakes, encodes and renders the atlas-textured scan for a set of held-out views. Use: Bake every
// frame in order, FinishBaking once, then Render any (view, frame) in frame order per view.
class AtlasTexturedScan {
 public:
  // `scan`: the run's first scan frame (topology, face labels, vertex colours). One video per
  // entry of `view_names`, written to video_dir/atlas_<name>.mp4 (kept: what the export would
  // stream). Throws InputError for a malformed scan, OutputError when ffmpeg cannot be started,
  // RenderContextError without GL.
  AtlasTexturedScan(const Mesh& scan, const std::vector<std::string>& view_names, const std::string& video_dir,
                    const AtlasTexturingOptions& options);
  ~AtlasTexturedScan();
  AtlasTexturedScan(const AtlasTexturedScan&) = delete;
  AtlasTexturedScan& operator=(const AtlasTexturedScan&) = delete;

  // Bakes one frame (the scan's vertices in it) from the input cameras, images and masks, once per
  // view with that view's per-camera colour gains (view_gains[v]; empty = none), and appends the
  // atlases to the views' videos. Returns the index of the frame (0, 1, ...).
  int Bake(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras, const std::vector<Image>& images,
           const std::vector<Image>& masks, const std::vector<std::vector<Eigen::Vector3d>>& view_gains);

  // Closes the videos and opens them for decoding. Throws OutputError when ffmpeg failed.
  void FinishBaking();

  // The scan (vertices of frame `index`) rendered with view `view`'s decoded atlas of that frame
  // into `camera`: unlit colour (equal to the texture) and silhouette, background black.
  RenderResult Render(int view, int index, const RowMatrixX3d& vertices, const Camera& camera);

  const UvAtlasStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One line for reports, e.g. "atlas 2048 px (74 charts, texel use 0.43, stretch 1.01), H.264 crf 18".
std::string DescribeAtlasTexturing(const AtlasTexturingOptions& options, const UvAtlasStats& stats);

}  // namespace confluent
