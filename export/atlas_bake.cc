#include "export/atlas_bake.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"

namespace confluent {

struct AtlasBaker::Impl {
  // A texel inside a UV triangle: its pixel (row-major, top row first), face and barycentric
  // coordinates of corners 1 and 2.
  struct Sample {
    std::int32_t pixel, face;
    float b1, b2;
  };
  // A gutter texel filled from `count` already filled neighbours sources[first..first+count).
  struct Fill {
    std::int32_t pixel, first, count;
  };
  int size = 0;
  RowMatrixX3i faces;
  RowMatrixX3f colors;  // per vertex, [0, 1]; empty: fallback
  Eigen::Vector3f fallback;
  std::vector<Sample> samples;
  std::vector<Fill> fills;
  std::vector<std::int32_t> sources;
  std::vector<std::int32_t> rest;  // texels neither covered nor reached by the fill rings
  std::unique_ptr<ProjectiveTexturer> texturer;
  RowMatrixX3f points, normals;
  std::vector<std::uint8_t> rgb, seen;
  bool baked = false;

  Image Compose() {
    Image out(size, size, 3);
    std::uint8_t* data = out.data.data();
    double sum[3] = {0, 0, 0};
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      std::uint8_t* texel = data + 3 * static_cast<std::size_t>(s.pixel);
      if (seen[i]) {
        std::copy_n(rgb.data() + 3 * i, 3, texel);
      } else {
        Eigen::Vector3f c = fallback;
        if (colors.rows() > 0) {
          const float b0 = 1.0f - s.b1 - s.b2;
          c = b0 * colors.row(faces(s.face, 0)).transpose() + s.b1 * colors.row(faces(s.face, 1)).transpose() +
              s.b2 * colors.row(faces(s.face, 2)).transpose();
        }
        for (int k = 0; k < 3; ++k)
          texel[k] = static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(c[k], 0.0f, 1.0f)));
      }
      for (int k = 0; k < 3; ++k) sum[k] += texel[k];
    }
    for (const Fill& fill : fills) {
      int total[3] = {0, 0, 0};
      for (int j = 0; j < fill.count; ++j)
        for (int k = 0; k < 3; ++k) total[k] += data[3 * static_cast<std::size_t>(sources[fill.first + j]) + k];
      for (int k = 0; k < 3; ++k)
        data[3 * static_cast<std::size_t>(fill.pixel) + k] =
            static_cast<std::uint8_t>((total[k] + fill.count / 2) / fill.count);
    }
    std::uint8_t mean[3];
    for (int k = 0; k < 3; ++k)
      mean[k] = static_cast<std::uint8_t>(samples.empty() ? 0 : std::lround(sum[k] / samples.size()));
    for (std::int32_t pixel : rest) std::copy_n(mean, 3, data + 3 * static_cast<std::size_t>(pixel));
    return out;
  }
};

AtlasBaker::AtlasBaker(const Mesh& mesh, const UvAtlas& atlas, const ProjectiveTextureOptions& texture,
                       const MeshRendererOptions& renderer)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  texture.Check();
  if (atlas.face_uvs.rows() != mesh.faces.rows() || atlas.size_px <= 0)
    throw InputError("mesh", "the UV atlas has " + std::to_string(atlas.face_uvs.rows()) + " faces, the mesh " +
                                 std::to_string(mesh.faces.rows()));
  if (atlas.uvs.rows() == 0 || atlas.face_uvs.minCoeff() < 0 || atlas.face_uvs.maxCoeff() >= atlas.uvs.rows())
    throw InputError("mesh", "the UV atlas has a texture coordinate index out of range");
  s.texturer = std::make_unique<ProjectiveTexturer>(mesh, texture, renderer);  // validates the mesh
  s.size = atlas.size_px;
  s.faces = mesh.faces;
  if (mesh.has_colors()) s.colors = mesh.colors.cwiseMax(0.0f).cwiseMin(1.0f);
  s.fallback = texture.fallback_color.cast<float>();
  const int size = s.size;
  const std::size_t texels = static_cast<std::size_t>(size) * size;
  // Texel centres inside UV triangles (the first face wins on shared samples).
  std::vector<std::int8_t> state(texels, 0);  // 0 empty, 1 covered or filled
  for (int f = 0; f < mesh.num_faces(); ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = atlas.uvs.row(atlas.face_uvs(f, k)).transpose() * size - Eigen::Vector2d(0.5, 0.5);
    const double area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
    if (area2 == 0.0) continue;
    const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({p[0].x(), p[1].x(), p[2].x()}))));
    const int x1 = std::min(size - 1, static_cast<int>(std::floor(std::max({p[0].x(), p[1].x(), p[2].x()}))));
    const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({p[0].y(), p[1].y(), p[2].y()}))));
    const int y1 = std::min(size - 1, static_cast<int>(std::floor(std::max({p[0].y(), p[1].y(), p[2].y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d q(x, y);
        auto edge = [&](int a, int b) {
          return ((p[b] - p[a]).x() * (q - p[a]).y() - (p[b] - p[a]).y() * (q - p[a]).x()) / area2;
        };
        const double b0 = edge(1, 2), b1 = edge(2, 0), b2 = edge(0, 1);
        if (b0 < 0 || b1 < 0 || b2 < 0) continue;
        const std::int32_t pixel = (size - 1 - y) * size + x;  // top row = v = 1
        if (state[pixel]) continue;
        state[pixel] = 1;
        s.samples.push_back({pixel, f, static_cast<float>(b1), static_cast<float>(b2)});
      }
  }
  // Gutter rings: each ring's texels average their filled 8-neighbours of earlier rings.
  constexpr int kFillRings = 16;
  std::vector<std::int32_t> frontier;
  for (const Impl::Sample& sample : s.samples) frontier.push_back(sample.pixel);
  for (int ring = 0; ring < kFillRings && !frontier.empty(); ++ring) {
    std::vector<std::int32_t> next;
    for (std::int32_t pixel : frontier) {
      const int x = pixel % size, y = pixel / size;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
          const std::int32_t neighbour = ny * size + nx;
          if (state[neighbour] == 0) {
            state[neighbour] = 2;  // in this ring
            next.push_back(neighbour);
          }
        }
    }
    for (std::int32_t pixel : next) {
      const int x = pixel % size, y = pixel / size;
      Impl::Fill fill{pixel, static_cast<std::int32_t>(s.sources.size()), 0};
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
          if (state[ny * size + nx] == 1) s.sources.push_back(ny * size + nx), ++fill.count;
        }
      s.fills.push_back(fill);
    }
    for (std::int32_t pixel : next) state[pixel] = 1;
    frontier.swap(next);
  }
  for (std::size_t pixel = 0; pixel < texels; ++pixel)
    if (state[pixel] == 0) s.rest.push_back(static_cast<std::int32_t>(pixel));
  s.points.resize(static_cast<Eigen::Index>(s.samples.size()), 3);
  s.normals.resize(static_cast<Eigen::Index>(s.samples.size()), 3);
}

AtlasBaker::~AtlasBaker() = default;

Image AtlasBaker::Bake(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                       const std::vector<Image>& images, const std::vector<Image>& masks) {
  Impl& s = *impl_;
  s.texturer->SetFrame(vertices, cameras, images, masks);  // checks the vertices
  const int m = static_cast<int>(s.faces.rows());
  RowMatrixX3f face_normals(m, 3);
  for (int f = 0; f < m; ++f) {
    const Eigen::Vector3d a = vertices.row(s.faces(f, 0)), b = vertices.row(s.faces(f, 1)),
                          c = vertices.row(s.faces(f, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);
    const double length = n.norm();
    n = length > 0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d(0, 0, 1);
    face_normals.row(f) = n.transpose().cast<float>();
  }
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    const Impl::Sample& sample = s.samples[i];
    const double b1 = sample.b1, b2 = sample.b2, b0 = 1.0 - b1 - b2;
    const Eigen::Index row = static_cast<Eigen::Index>(i);
    s.points.row(row) = (b0 * vertices.row(s.faces(sample.face, 0)) + b1 * vertices.row(s.faces(sample.face, 1)) +
                         b2 * vertices.row(s.faces(sample.face, 2)))
                            .cast<float>();
    s.normals.row(row) = face_normals.row(sample.face);
  }
  s.baked = true;
  s.texturer->BlendSurfacePoints(s.points, s.normals, kBakeViewDistanceM, &s.rgb, &s.seen);
  return s.Compose();
}

Image AtlasBaker::Rebake(const std::vector<Eigen::Vector3d>& view_gains) {
  Impl& s = *impl_;
  if (!s.baked) throw UsageError("AtlasBaker::Rebake called before Bake");
  s.texturer->SetViewGains(view_gains);
  s.texturer->BlendSurfacePoints(s.points, s.normals, kBakeViewDistanceM, &s.rgb, &s.seen);
  return s.Compose();
}

int AtlasBaker::covered_texels() const { return static_cast<int>(impl_->samples.size()); }

}  // namespace confluent
