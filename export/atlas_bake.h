#pragma once
// Per-frame atlas textures: each frame's projective texture (render/projective_texture.h: the
// same visibility, ULR blending, feathering, grazing ramp and colour gains as `render`) baked
// into the scan's UV atlas (export/uv_atlas.h), with the mesh's own vertex colours where no
// camera sees the surface, and the gutters around the charts filled from the charts.
//
// Each atlas texel whose centre lies inside a UV triangle stands for the surface point with the
// same barycentric coordinates on that face; its colour is the blend a viewer straight along the
// face's normal sees (the novel view's centre kBakeViewDistanceM out along the normal).

#include <memory>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "export/uv_atlas.h"
#include "render/projective_texture.h"
#include "render/renderer.h"

namespace confluent {

// How far out along the normal the baking viewer sits, metres (the angle penalty does not depend
// on it; the optional ULR resolution penalty does).
constexpr double kBakeViewDistanceM = 2.5;

// Bakes the frames of one mesh sequence (fixed topology) into its atlas. The texel -> (face,
// barycentric) map and the gutter-filling plan are computed once, at construction. Owns a
// ProjectiveTexturer (GL state): not thread-safe.
class AtlasBaker {
 public:
  // `mesh`: topology, vertex colours for unseen surface (else texture.fallback_color) and first
  // vertices; `atlas`: its UVs (BuildUvAtlas of the same mesh). Throws InputError("mesh") for a
  // malformed mesh or an atlas of another face count, UsageError for bad options and
  // RenderContextError when no GL context can be created.
  AtlasBaker(const Mesh& mesh, const UvAtlas& atlas, const ProjectiveTextureOptions& texture = {},
             const MeshRendererOptions& renderer = {});
  ~AtlasBaker();
  AtlasBaker(const AtlasBaker&) = delete;
  AtlasBaker& operator=(const AtlasBaker&) = delete;

  // One frame's atlas: RGB8, size_px x size_px, top image row = v = 1. Texels outside the charts
  // are filled from the chart texels up to 16 texels away (ring by ring, each texel the mean of its
  // filled 8-neighbours), the rest with
  // the mean chart colour, so that bilinear and mip-mapped sampling do not bleed. `vertices`:
  // this frame's positions (n x 3, world, metres); cameras, images and masks as
  // ProjectiveTexturer::SetFrame (and throws as it does).
  Image Bake(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras, const std::vector<Image>& images,
             const std::vector<Image>& masks = {});

  // The last Bake's frame baked again with per-camera RGB factors on top of the colour balance
  // (ProjectiveTexturer::SetViewGains, SetFrame's camera order; empty = none), without redrawing
  // the depth maps: e.g. the input colours matched to a held-out camera's response. The factors
  // stay for later Bake calls until changed. Throws UsageError before Bake or for a wrong count.
  Image Rebake(const std::vector<Eigen::Vector3d>& view_gains);

  // Atlas texels whose centre lies inside a UV triangle (the rest is gutter).
  int covered_texels() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
