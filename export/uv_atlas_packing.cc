// The atlas's chart orientation and skyline packing (export/uv_atlas_packing.h).

#include "export/uv_atlas_packing.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace confluent::uv_atlas_internal {

void OrientChart(Chart* chart) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : chart->uv) mean += p;
  mean /= static_cast<double>(chart->uv.size());
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d& p : chart->uv) covariance += (p - mean) * (p - mean).transpose();
  Eigen::Matrix2d R = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance).eigenvectors().transpose();
  R.row(0).swap(R.row(1));  // largest eigenvector first: along u
  if (R.determinant() < 0) R.row(1) *= -1;  // a rotation, not a mirror
  Eigen::Vector2d lo(1e30, 1e30), hi(-1e30, -1e30);
  for (Eigen::Vector2d& p : chart->uv) {
    p = R * (p - mean);
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  if (hi.y() - lo.y() > hi.x() - lo.x()) {  // rotate by 90 degrees
    for (Eigen::Vector2d& p : chart->uv) p = Eigen::Vector2d(-p.y(), p.x());
    lo = hi = chart->uv[0];
    for (const Eigen::Vector2d& p : chart->uv) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  chart->min_u = lo.x(), chart->min_v = lo.y();
  chart->width = hi.x() - lo.x(), chart->height = hi.y() - lo.y();
}

bool Pack(std::vector<Chart>* charts, const std::vector<int>& order, double texels_per_m, int size, int padding) {
  struct Segment {
    int x, y, width;
  };
  std::vector<Segment> skyline = {{0, 0, size}};
  for (int c : order) {
    Chart& chart = (*charts)[c];
    const int w = static_cast<int>(std::ceil(chart.width * texels_per_m)) + 1 + 2 * padding;
    const int h = static_cast<int>(std::ceil(chart.height * texels_per_m)) + 1 + 2 * padding;
    int best_top = size + 1, best_x = 0, best_y = 0, best_i = -1;
    bool best_turned = false;
    for (int turned = 0; turned < 2; ++turned) {
      const int bw = turned ? h : w, bh = turned ? w : h;
      for (std::size_t i = 0; i < skyline.size(); ++i) {
        const int x = skyline[i].x;
        if (x + bw > size) break;
        int y = 0;
        for (std::size_t j = i; j < skyline.size() && skyline[j].x < x + bw; ++j) y = std::max(y, skyline[j].y);
        if (y + bh > size) continue;
        if (y + bh < best_top || (y + bh == best_top && x < best_x)) {
          best_top = y + bh, best_x = x, best_y = y, best_i = static_cast<int>(i), best_turned = turned;
        }
      }
    }
    if (best_i < 0) return false;
    const int bw = best_turned ? h : w;
    chart.x = best_x, chart.y = best_y, chart.turned = best_turned;
    // The new segment replaces the ones it covers (the last one is trimmed).
    std::vector<Segment> next(skyline.begin(), skyline.begin() + best_i);
    next.push_back({best_x, best_top, bw});
    for (std::size_t j = best_i; j < skyline.size(); ++j) {
      const int end = skyline[j].x + skyline[j].width;
      if (end <= best_x + bw) continue;
      const int start = std::max(skyline[j].x, best_x + bw);
      next.push_back({start, skyline[j].y, end - start});
    }
    skyline.clear();
    for (const Segment& segment : next)
      if (!skyline.empty() && skyline.back().y == segment.y) skyline.back().width += segment.width;
      else skyline.push_back(segment);
  }
  return true;
}

}  // namespace confluent::uv_atlas_internal
