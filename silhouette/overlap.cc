#include "silhouette/overlap.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "calib/capture.h"
#include "calib/rig_check.h"  // MaskIoU
#include "core/cv_interop.h"

namespace confluent {

Image RasterizeSilhouette(const Mesh& mesh, const Camera& camera, int downscale) {
  downscale = std::max(1, downscale);
  const int width = std::max(1, camera.width / downscale), height = std::max(1, camera.height / downscale);
  Image out(width, height, 1);
  cv::Mat target = AsCvMat(out);
  const double sx = static_cast<double>(width) / camera.width, sy = static_cast<double>(height) / camera.height;
  constexpr int kShift = 4;
  const double fixed = 1 << kShift;
  std::vector<cv::Point> projected(mesh.num_vertices());
  std::vector<char> valid(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    Eigen::Vector2d pixel;
    if (!camera.ProjectChecked(mesh.vertices.row(v).transpose(), &pixel)) continue;
    const double x = ((pixel.x() + 0.5) * sx - 0.5) * fixed, y = ((pixel.y() + 0.5) * sy - 0.5) * fixed;
    if (std::abs(x) > 1e8 || std::abs(y) > 1e8) continue;
    projected[v] = cv::Point(static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)));
    valid[v] = 1;
  }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int a = mesh.faces(f, 0), b = mesh.faces(f, 1), c = mesh.faces(f, 2);
    if (!valid[a] || !valid[b] || !valid[c]) continue;
    const cv::Point triangle[3] = {projected[a], projected[b], projected[c]};
    cv::fillConvexPoly(target, triangle, 3, cv::Scalar(255), cv::LINE_8, kShift);
  }
  return out;
}

Image RasterizeClosedMesh(const Mesh& mesh, const Camera& camera) {
  Image out(camera.width, camera.height, 1);
  const int n = mesh.num_vertices();
  std::vector<Eigen::Vector2d> pixels(n);
  std::vector<char> valid(n, 0);
  for (int v = 0; v < n; ++v) valid[v] = camera.ProjectChecked(mesh.vertices.row(v).transpose(), &pixels[v]);
  const Eigen::Vector3d centre = camera.center_in_world();
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int a = mesh.faces(f, 0), b = mesh.faces(f, 1), c = mesh.faces(f, 2);
    if (!valid[a] || !valid[b] || !valid[c]) continue;
    const Eigen::Vector3d pa = mesh.vertices.row(a), pb = mesh.vertices.row(b), pc = mesh.vertices.row(c);
    if ((pb - pa).cross(pc - pa).dot(pa - centre) > 0.0) continue;  // faces away
    const Eigen::Vector2d& p0 = pixels[a];
    const Eigen::Vector2d& p1 = pixels[b];
    const Eigen::Vector2d& p2 = pixels[c];
    const double area = (p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x();
    if (area == 0.0 || !std::isfinite(area)) continue;
    const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({p0.x(), p1.x(), p2.x()}))));
    const int x1 = std::min(out.width - 1, static_cast<int>(std::floor(std::max({p0.x(), p1.x(), p2.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({p0.y(), p1.y(), p2.y()}))));
    const int y1 = std::min(out.height - 1, static_cast<int>(std::floor(std::max({p0.y(), p1.y(), p2.y()}))));
    const double sign = area > 0.0 ? 1.0 : -1.0;
    // The edge function sign * ((to - from).x (y - from.y) - (to - from).y (x - from.x)) of each
    // edge, its first product computed once per row (the same operations, the same result).
    const double dx01 = p1.x() - p0.x(), dy01 = p1.y() - p0.y(), dx12 = p2.x() - p1.x(), dy12 = p2.y() - p1.y();
    const double dx20 = p0.x() - p2.x(), dy20 = p0.y() - p2.y();
    for (int y = y0; y <= y1; ++y) {
      const double row01 = dx01 * (y - p0.y()), row12 = dx12 * (y - p1.y()), row20 = dx20 * (y - p2.y());
      std::uint8_t* row = out.data.data() + static_cast<std::size_t>(y) * out.width;
      for (int x = x0; x <= x1; ++x)
        if (sign * (row01 - dy01 * (x - p0.x())) >= 0.0 && sign * (row12 - dy12 * (x - p1.x())) >= 0.0 &&
            sign * (row20 - dy20 * (x - p2.x())) >= 0.0)
          row[x] = 255;
    }
  }
  return out;
}

Image DownscaleMask(const Image& mask, int downscale) {
  if (downscale <= 1) return mask;
  const int width = std::max(1, mask.width / downscale), height = std::max(1, mask.height / downscale);
  cv::Mat small;
  cv::resize(AsCvMat(mask), small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  cv::threshold(small, small, 127, 255, cv::THRESH_BINARY);
  return ImageFromCvMat(small);
}

std::vector<double> SilhouetteIoUs(const Mesh& mesh, const Rig& rig, const std::vector<Image>& masks,
                                   const std::vector<bool>& use, int downscale) {
  std::vector<double> ious(rig.size(), -1.0);
  for (int c = 0; c < rig.size() && c < static_cast<int>(masks.size()); ++c) {
    if ((!use.empty() && !use[c]) || masks[c].empty()) continue;
    const Camera& camera = rig.cameras[c];
    const int factor = downscale > 0 ? downscale : std::max(1, static_cast<int>(std::lround(masks[c].width / 256.0)));
    const Image rendered = RasterizeClosedMesh(
        mesh, ResizedCamera(camera, std::max(1, camera.width / factor), std::max(1, camera.height / factor)));
    const Image mask = DownscaleMask(masks[c], factor);
    if (mask.width != rendered.width || mask.height != rendered.height) continue;
    ious[c] = MaskIoU(rendered, mask);
  }
  return ious;
}

double MeanSilhouetteIoU(const std::vector<double>& ious) {
  double sum = 0.0;
  int n = 0;
  for (double iou : ious)
    if (iou >= 0.0) {
      sum += iou;
      ++n;
    }
  return n ? sum / n : 0.0;
}

long CountForeground(const Image& mask) {
  if (mask.empty()) return 0;
  return cv::countNonZero(AsCvMat(mask));
}

Image DrawSilhouetteOverlay(const Image& image, const Image& rendered, const Image* mask) {
  Image rgb = ToRgb8(image);
  cv::Mat canvas = AsCvMat(rgb);
  auto outline = [&](const Image& m, const cv::Scalar& color) {
    cv::Mat binary = AsCvMat(m).clone();
    if (binary.size() != canvas.size()) cv::resize(binary, binary, canvas.size(), 0, 0, cv::INTER_NEAREST);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(binary, contours, cv::RETR_LIST, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(canvas, contours, -1, color, std::max(1, canvas.cols / 512), cv::LINE_AA);
  };
  if (mask && !mask->empty()) outline(*mask, cv::Scalar(0, 255, 0));
  outline(rendered, cv::Scalar(255, 40, 40));
  return rgb;
}

}  // namespace confluent
