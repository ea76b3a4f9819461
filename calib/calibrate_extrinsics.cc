// Extrinsic chaining for CalibrateRig: the consensus relative pose of two cameras over the
// frames both saw, allowing for the board's half-turn ambiguity; CalibrateRig chains these edges
// into a spanning tree from the reference camera.

#include <algorithm>
#include <array>

#include "calib/calibrate_internal.h"

namespace confluent {
namespace calibrate_internal {

namespace {

bool PosesAgree(const Pose& x, const Pose& y, double rotation_deg) {
  if (RotationAngleDeg(x.linear(), y.linear()) > rotation_deg) return false;
  const double scale = std::max({x.translation().norm(), y.translation().norm(), 1e-6});
  return (x.translation() - y.translation()).norm() <= 0.2 * scale;
}

}  // namespace

Edge PairConsensus(const CameraState& a, const CameraState& b, int index_a, int index_b, const Pose& turn,
                   double rotation_deg) {
  Edge edge;
  edge.a = index_a;
  edge.b = index_b;
  std::vector<std::array<Pose, 2>> candidates;
  for (const auto& [frame, view_a] : a.view_of_frame) {
    const auto found = b.view_of_frame.find(frame);
    if (found == b.view_of_frame.end()) continue;
    const Pose& pose_a = a.views[view_a].cam_from_board;
    const Pose& pose_b = b.views[found->second].cam_from_board;
    candidates.push_back({pose_a * pose_b.inverse(), pose_a * turn * pose_b.inverse()});
  }
  if (candidates.empty()) return edge;
  int best_count = -1, best_plain = -1;
  std::vector<int> best_choice;
  for (std::size_t f = 0; f < candidates.size(); ++f)
    for (int d = 0; d < 2; ++d) {
      std::vector<int> choice(candidates.size(), -1);
      int count = 0, plain = 0;
      for (std::size_t g = 0; g < candidates.size(); ++g)
        for (int e = 0; e < 2; ++e)
          if (PosesAgree(candidates[g][e], candidates[f][d], rotation_deg)) {
            choice[g] = e;
            ++count;
            plain += e == 0;
            break;
          }
      if (count > best_count || (count == best_count && plain > best_plain)) {
        best_count = count;
        best_plain = plain;
        best_choice = choice;
      }
    }
  Eigen::Matrix3d rotation_sum = Eigen::Matrix3d::Zero();
  Eigen::Vector3d translation_sum = Eigen::Vector3d::Zero();
  for (std::size_t g = 0; g < candidates.size(); ++g)
    if (best_choice[g] >= 0) {
      rotation_sum += candidates[g][best_choice[g]].linear();
      translation_sum += candidates[g][best_choice[g]].translation();
    }
  edge.weight = best_count;
  edge.a_from_b.linear() = ProjectToRotation(rotation_sum);
  edge.a_from_b.translation() = translation_sum / best_count;
  return edge;
}

}  // namespace calibrate_internal
}  // namespace confluent
