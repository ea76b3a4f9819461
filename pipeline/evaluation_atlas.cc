#include "pipeline/evaluation_atlas.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/video.h"
#include "export/atlas_bake.h"

namespace confluent {

struct AtlasTexturedScan::Impl {
  AtlasTexturingOptions options;
  Mesh textured;  // the scan with the atlas's UVs
  UvAtlas atlas;
  std::unique_ptr<AtlasBaker> baker;
  std::vector<std::string> paths;
  std::vector<std::unique_ptr<VideoWriter>> writers;  // per view, until FinishBaking
  std::vector<std::unique_ptr<VideoReader>> readers;
  // Per view: the last decoded frame and its index.
  std::vector<Image> decoded;
  std::vector<int> decoded_index;
  int frames = 0;
};

void AtlasTexturingOptions::Check() const {
  RequireOption(atlas_size_px >= 64 && atlas_size_px <= 16384, "AtlasTexturingOptions.atlas_size_px", atlas_size_px,
                "in [64, 16384]");
  RequireOption(supersampling >= 1 && supersampling <= 4, "AtlasTexturingOptions.supersampling", supersampling,
                "in [1, 4]");
  video.Check();
  texturing.Check();
}

AtlasTexturedScan::AtlasTexturedScan(const Mesh& scan, const std::vector<std::string>& view_names,
                                     const std::string& video_dir, const AtlasTexturingOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  Impl& s = *impl_;
  s.options = options;
  UvAtlasOptions atlas_options;
  atlas_options.size_px = options.atlas_size_px;
  s.atlas = BuildUvAtlas(scan, atlas_options);
  s.textured = WithAtlasUvs(scan, s.atlas);
  s.baker = std::make_unique<AtlasBaker>(scan, s.atlas, options.texturing);
  std::filesystem::create_directories(video_dir);
  for (const std::string& name : view_names) {
    s.paths.push_back((std::filesystem::path(video_dir) / ("atlas_" + name + ".mp4")).string());
    s.writers.push_back(
        std::make_unique<VideoWriter>(s.paths.back(), options.atlas_size_px, options.atlas_size_px, options.video));
  }
}

AtlasTexturedScan::~AtlasTexturedScan() = default;

int AtlasTexturedScan::Bake(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                            const std::vector<Image>& images, const std::vector<Image>& masks,
                            const std::vector<std::vector<Eigen::Vector3d>>& view_gains) {
  Impl& s = *impl_;
  if (!s.readers.empty()) throw UsageError("AtlasTexturedScan::Bake after FinishBaking");
  const Image atlas = s.baker->Bake(vertices, cameras, images, masks);
  const bool gains = std::any_of(view_gains.begin(), view_gains.end(), [](const auto& g) { return !g.empty(); });
  for (std::size_t v = 0; v < s.writers.size(); ++v)
    s.writers[v]->Write(gains ? s.baker->Rebake(v < view_gains.size() ? view_gains[v] : std::vector<Eigen::Vector3d>())
                              : atlas);
  return s.frames++;
}

void AtlasTexturedScan::FinishBaking() {
  Impl& s = *impl_;
  for (std::unique_ptr<VideoWriter>& writer : s.writers) writer->Close();
  s.writers.clear();
  for (const std::string& path : s.paths) s.readers.push_back(std::make_unique<VideoReader>(path));
  s.decoded.assign(s.paths.size(), Image());
  s.decoded_index.assign(s.paths.size(), -1);
}

RenderResult AtlasTexturedScan::Render(int view, int index, const RowMatrixX3d& vertices, const Camera& camera) {
  Impl& s = *impl_;
  if (s.readers.empty()) throw UsageError("AtlasTexturedScan::Render before FinishBaking");
  if (view < 0 || view >= static_cast<int>(s.readers.size()) || index < 0 || index >= s.frames)
    throw UsageError("AtlasTexturedScan::Render: no view " + std::to_string(view) + " frame " + std::to_string(index));
  if (s.decoded_index[view] != index) {
    s.decoded[view] = s.readers[view]->ReadFrame(index);
    s.decoded_index[view] = index;
  }
  // MeshRenderer keeps a texture for the lifetime of a mesh: one renderer per rendered frame.
  MeshRenderer renderer;
  Mesh mesh = s.textured;
  mesh.vertices = vertices;
  const int handle = renderer.AddMesh(mesh, "scan (atlas)", s.decoded[view]);
  RenderRequest request;
  request.silhouette = true;
  request.meshes = {handle};
  request.cull_back_faces = s.options.texturing.cull_back_faces;
  request.shading.lit = false;
  // 8-bit textures are decoded from sRGB when sampled; encoding the output gives the texture back.
  request.shading.srgb_output = true;
  request.shading.background = Eigen::Vector3d::Zero();
  RenderResult result = renderer.Render(camera, request);  // the silhouette: pixel centres, as projective
  const int n = s.options.supersampling;
  if (n == 1) return result;
  // Colour: the mean of the covered samples of an n x n grid per pixel (the camera with K scaled
  // so that sample (n x + i, n y + j) has its centre at (x + (i + 0.5) / n - 0.5, ...)).
  Camera fine = camera;
  Eigen::Matrix3d scale = Eigen::Matrix3d::Identity();
  scale(0, 0) = scale(1, 1) = n;
  scale(0, 2) = scale(1, 2) = 0.5 * (n - 1);
  fine.K = scale * camera.K;
  fine.width = n * camera.width;
  fine.height = n * camera.height;
  const RenderResult samples = renderer.Render(fine, request);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      int sum[3] = {0, 0, 0}, count = 0;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          if (!samples.silhouette.at<std::uint8_t>(n * x + i, n * y + j)) continue;
          ++count;
          for (int c = 0; c < 3; ++c) sum[c] += samples.color.at<std::uint8_t>(n * x + i, n * y + j, c);
        }
      if (count == 0) continue;
      for (int c = 0; c < 3; ++c) result.color.at<std::uint8_t>(x, y, c) = static_cast<std::uint8_t>((sum[c] + count / 2) / count);
    }
  return result;
}

const UvAtlasStats& AtlasTexturedScan::stats() const { return impl_->atlas.stats; }

std::string DescribeAtlasTexturing(const AtlasTexturingOptions& options, const UvAtlasStats& stats) {
  char line[200];
  std::snprintf(line, sizeof line, "atlas %d px (%d charts, texel use %.2f, stretch %.3f), H.264 crf %d %s, %dx%d samples",
                options.atlas_size_px, stats.charts, stats.texel_use, stats.stretch_mean, options.video.crf,
                options.video.preset.c_str(), options.supersampling, options.supersampling);
  return line;
}

}  // namespace confluent
