// ProjectiveTexturer's colour balance: least-squares per-camera RGB gains from surface points
// that several cameras see well.

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "render/projective_texture_impl.h"

namespace confluent {
namespace {

// Bilinear RGB sample of an RGB8 image at a pixel position (centres at integers), in [0,1].
Eigen::Vector3d SampleRgb(const Image& image, const Eigen::Vector2d& pixel) {
  const double x = std::clamp(pixel.x(), 0.0, image.width - 1.0), y = std::clamp(pixel.y(), 0.0, image.height - 1.0);
  const int x0 = std::min(static_cast<int>(x), image.width - 2 < 0 ? 0 : image.width - 2);
  const int y0 = std::min(static_cast<int>(y), image.height - 2 < 0 ? 0 : image.height - 2);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const double fx = x - x0, fy = y - y0;
  Eigen::Vector3d value;
  for (int c = 0; c < 3; ++c) {
    const double top = (1 - fx) * image.at<std::uint8_t>(x0, y0, c) + fx * image.at<std::uint8_t>(x1, y0, c);
    const double bottom = (1 - fx) * image.at<std::uint8_t>(x0, y1, c) + fx * image.at<std::uint8_t>(x1, y1, c);
    value[c] = ((1 - fy) * top + fy * bottom) / 255.0;
  }
  return value;
}
}  // namespace

// Least-squares per-camera RGB gains from surface points seen well by several cameras.
std::vector<Eigen::Vector3d> ProjectiveTexturer::Impl::FitGains(const RowMatrixX3d& vertices,
                                                                const std::vector<CameraFrame>& frames) const {
  const int n = static_cast<int>(frames.size());
  std::vector<Eigen::Vector3d> result(n, Eigen::Vector3d::Ones());
  if (n < 2) return result;
  const int stride = std::max(1, num_vertices / options.colour_balance_samples);
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  int equations = 0;
  std::vector<int> seen;
  std::vector<Eigen::Vector3d> logs;
  for (int v = 0; v < num_vertices; v += stride) {
    const Eigen::Vector3d X = vertices.row(v).transpose();
    seen.clear();
    logs.clear();
    for (int i = 0; i < n; ++i) {
      const CameraFrame& frame = frames[i];
      Eigen::Vector2d pixel;
      if (!frame.camera.ProjectChecked(X, &pixel)) continue;
      const int px = static_cast<int>(std::lround(pixel.x())), py = static_cast<int>(std::lround(pixel.y()));
      if (px < 0 || py < 0 || px >= frame.camera.width || py >= frame.camera.height) continue;
      // The same pixel in the depth and feather maps (texel centres at +0.5).
      const Camera& map = frame.map_camera;
      const int mx = std::min(map.width - 1, static_cast<int>((px + 0.5) * map.width / frame.camera.width));
      const int my = std::min(map.height - 1, static_cast<int>((py + 0.5) * map.height / frame.camera.height));
      const float depth = frame.depth(mx, my);
      if (depth <= 0.0f || frame.camera.PointInCamera(X).z() > depth + options.depth_bias_m + proxy_bias_m)
        continue;
      if (frame.feather(mx, my) < 0.99f) continue;
      const Eigen::Vector3d rgb = SampleRgb(*frame.image, pixel);
      if (rgb.minCoeff() < 0.03 || rgb.maxCoeff() > 0.97) continue;  // log of clipped values is unreliable
      seen.push_back(i);
      logs.push_back(rgb.array().log().matrix());
    }
    // Pairwise equations: log g_a - log g_b = log c_b - log c_a.
    for (std::size_t a = 0; a < seen.size(); ++a)
      for (std::size_t b = a + 1; b < seen.size(); ++b) {
        const int i = seen[a], j = seen[b];
        normal(i, i) += 1;
        normal(j, j) += 1;
        normal(i, j) -= 1;
        normal(j, i) -= 1;
        const Eigen::Vector3d d = logs[b] - logs[a];
        rhs.row(i) += d.transpose();
        rhs.row(j) -= d.transpose();
        ++equations;
      }
  }
  if (equations == 0) return result;
  // Weak prior towards gain 1 keeps cameras without overlaps (and the global scale) fixed.
  normal += 1e-3 * equations / n * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd log_gains = normal.ldlt().solve(rhs);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) result[i][c] = std::clamp(std::exp(log_gains(i, c)), 0.5, 2.0);
  return result;
}

}  // namespace confluent
