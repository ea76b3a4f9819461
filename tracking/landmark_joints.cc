#include "tracking/landmark_joints.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "core/error.h"

namespace confluent {

using Eigen::Vector2d;
using Eigen::Vector3d;

void LandmarkJointsOptions::Check() const {
  RequireOption(min_visibility >= 0 && min_visibility <= 1, "LandmarkJointsOptions.min_visibility", min_visibility,
                "in [0, 1]");
  RequireOption(agree_fraction > 0 && agree_fraction < 1, "LandmarkJointsOptions.agree_fraction", agree_fraction,
                "in (0, 1)");
  RequireOption(min_cameras >= 2, "LandmarkJointsOptions.min_cameras", min_cameras, ">= 2");
}

int LandmarkJoints::num_known() const {
  return static_cast<int>(std::count_if(cameras.begin(), cameras.end(), [](int n) { return n > 0; }));
}

namespace {

// The limb joints placed, each with its BlazePose landmark on the person's left and right.
struct JointPair {
  int left_joint, right_joint;
  int left_landmark, right_landmark;
};
constexpr JointPair kPairs[] = {
    {kJointLeftShoulder, kJointRightShoulder, 11, 12}, {kJointLeftElbow, kJointRightElbow, 13, 14},
    {kJointLeftWrist, kJointRightWrist, 15, 16},       {kJointLeftHip, kJointRightHip, 23, 24},
    {kJointLeftKnee, kJointRightKnee, 25, 26},         {kJointLeftAnkle, kJointRightAnkle, 27, 28},
    {kJointLeftToe, kJointRightToe, 31, 32},
};
static_assert(2 * std::size(kPairs) == kTriangulatedJoints);
constexpr int kNose = 0;
constexpr int kLeftPinky = 17, kLeftIndex = 19;  // the knuckles; the right ones follow
constexpr int kLeftHeel = 29, kLeftToe = 31;

// The landmark on the other side of the body (the nose has none).
int Twin(int landmark) { return landmark == kNose ? kNose : (landmark % 2 ? landmark + 1 : landmark - 1); }

// The point closest (least squares) to the rays of `pixels` seen by `cameras`.
Vector3d ClosestToRays(const Rig& rig, const std::vector<int>& cameras, const std::vector<Vector2d>& pixels) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Vector3d b = Vector3d::Zero();
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const Camera& camera = rig.cameras[cameras[i]];
    const Vector3d d = camera.RayInWorld(pixels[i]).normalized();
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += P;
    b += P * camera.center_in_world();
  }
  return A.ldlt().solve(b);
}

double ReprojectionPx(const Camera& camera, const Vector3d& point, const Vector2d& pixel) {
  Vector2d projected;
  if (!camera.ProjectChecked(point, &projected)) return std::numeric_limits<double>::infinity();
  return (projected - pixel).norm();
}

// Cameras' observations of one point, or of a pair whose sides a camera may swap.
struct View {
  int camera;
  Vector2d pixel[2];  // [1] only for a pair
  double tolerance_px;
};

// A consensus: the point(s), each view's swap (pairs only; 0 = as given) and agreement.
struct Consensus {
  Vector3d point[2];
  std::vector<int> swap;
  std::vector<bool> agrees;
  int count = 0;
  double error = std::numeric_limits<double>::infinity();
  double rms_px = 0;
};

Consensus Score(const Rig& rig, const std::vector<View>& views, const Vector3d* points, bool pair) {
  Consensus c;
  c.point[0] = points[0];
  c.point[1] = pair ? points[1] : points[0];
  c.swap.assign(views.size(), 0);
  c.agrees.assign(views.size(), false);
  c.error = 0;
  double squares = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    const Camera& camera = rig.cameras[views[v].camera];
    double best = std::numeric_limits<double>::infinity();
    for (int s = 0; s < (pair ? 2 : 1); ++s) {
      double e = ReprojectionPx(camera, points[0], views[v].pixel[s]);
      if (pair) e = std::max(e, ReprojectionPx(camera, points[1], views[v].pixel[1 - s]));
      if (e < best) {
        best = e;
        c.swap[v] = s;
      }
    }
    if (best <= views[v].tolerance_px) {
      c.agrees[v] = true;
      ++c.count;
      c.error += best;
      squares += best * best;
    }
  }
  c.rms_px = c.count ? std::sqrt(squares / c.count) : 0.0;
  return c;
}

// The point (or pair) most views agree with (then the smallest error): proposed by every two
// views (for a pair, the second as given and swapped), then triangulated again from all the
// views that agree.
Consensus Agree(const Rig& rig, const std::vector<View>& views, bool pair) {
  Consensus best;
  best.count = 0;
  for (std::size_t i = 0; i < views.size(); ++i)
    for (std::size_t j = i + 1; j < views.size(); ++j)
      for (int s = 0; s < (pair ? 2 : 1); ++s) {
        const std::vector<int> cams = {views[i].camera, views[j].camera};
        const Vector3d points[2] = {ClosestToRays(rig, cams, {views[i].pixel[0], views[j].pixel[s]}),
                                    ClosestToRays(rig, cams, {views[i].pixel[1], views[j].pixel[1 - s]})};
        const Consensus c = Score(rig, views, points, pair);
        if (c.count > best.count || (c.count == best.count && c.count > 0 && c.error < best.error)) best = c;
      }
  if (best.count < 2) return best;
  std::vector<int> cams;
  std::vector<Vector2d> px[2];
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (!best.agrees[v]) continue;
    cams.push_back(views[v].camera);
    for (int k = 0; k < 2; ++k) px[k].push_back(views[v].pixel[k ^ best.swap[v]]);
  }
  const Vector3d points[2] = {ClosestToRays(rig, cams, px[0]), ClosestToRays(rig, cams, px[1])};
  const Consensus refit = Score(rig, views, points, pair);
  return refit.count >= best.count ? refit : best;
}

double Tolerance(const Camera& camera, const LandmarkJointsOptions& options) {
  return options.agree_fraction * std::hypot(camera.width, camera.height);
}

bool Visible(const BodyLandmarks& view, int landmark, const LandmarkJointsOptions& options) {
  return view[landmark].z() >= options.min_visibility;
}

// The views of the pair (landmark, Twin(landmark)) in the cameras that see both.
std::vector<View> PairViews(const Rig& rig, const std::vector<const BodyLandmarks*>& views, int landmark,
                            const LandmarkJointsOptions& options) {
  std::vector<View> out;
  for (int c = 0; c < rig.size() && c < static_cast<int>(views.size()); ++c) {
    if (!views[c] || !Visible(*views[c], landmark, options) || !Visible(*views[c], Twin(landmark), options)) continue;
    out.push_back({c, {(*views[c])[landmark].head<2>().cast<double>(), (*views[c])[Twin(landmark)].head<2>().cast<double>()},
                   Tolerance(rig.cameras[c], options)});
  }
  return out;
}

// Horizontal part of v (world z up).
Vector3d Horizontal(const Vector3d& v) { return Vector3d(v.x(), v.y(), 0.0); }

}  // namespace

LandmarkJoints TriangulateLandmarkJoints(const Rig& rig, const std::vector<const BodyLandmarks*>& views,
                                         const LandmarkJointsOptions& options) {
  options.Check();
  LandmarkJoints out;
  out.position.assign(kNumBodyJoints, Vector3d::Zero());
  out.cameras.assign(kNumBodyJoints, 0);
  out.rms_px.assign(kNumBodyJoints, 0.0);
  int with_views = 0;
  for (int c = 0; c < rig.size() && c < static_cast<int>(views.size()); ++c) with_views += views[c] != nullptr;
  const int needed = std::max(2, std::min(options.min_cameras, with_views));
  // 1. Each camera's sides, relative to one of the shoulders ("side A"): from the shoulders'
  //    consensus, else the hips' (aligned with the shoulders').
  std::vector<int> swap(rig.size(), -1);  // -1: unsettled
  const std::vector<View> shoulder_views = PairViews(rig, views, 11, options);
  const Consensus shoulders = Agree(rig, shoulder_views, true);
  if (shoulders.count < needed) return out;
  for (std::size_t v = 0; v < shoulder_views.size(); ++v)
    if (shoulders.agrees[v]) swap[shoulder_views[v].camera] = shoulders.swap[v];
  const std::vector<View> hip_views = PairViews(rig, views, 23, options);
  const Consensus hips = Agree(rig, hip_views, true);
  if (hips.count >= needed) {
    const int align = (hips.point[0] - hips.point[1]).dot(shoulders.point[0] - shoulders.point[1]) < 0 ? 1 : 0;
    for (std::size_t v = 0; v < hip_views.size(); ++v)
      if (hips.agrees[v] && swap[hip_views[v].camera] < 0) swap[hip_views[v].camera] = hips.swap[v] ^ align;
  }
  // 2. Every landmark of side A (odd BlazePose index, or the nose) and side B, one point each.
  auto place = [&](int landmark_a, int side) {
    const int landmark = side ? Twin(landmark_a) : landmark_a;
    std::vector<View> seen;
    for (int c = 0; c < rig.size(); ++c) {
      if (swap[c] < 0) continue;
      const int own = swap[c] ? Twin(landmark) : landmark;  // what this camera calls it
      if (!Visible(*views[c], own, options)) continue;
      seen.push_back({c, {(*views[c])[own].head<2>().cast<double>(), Vector2d::Zero()}, Tolerance(rig.cameras[c], options)});
    }
    Consensus c = Agree(rig, seen, false);
    if (c.count < needed) c.count = 0;
    return c;
  };
  // 3. Which side is the person's left: the front is where the toes point (a detector looking at
  //    the back swaps the sides but still places the toes ahead of the heels), else the nose
  //    (less sure: from behind, a detector puts it on the back of the head).
  const Vector3d up(0, 0, 1);
  const Vector3d a_to_b = Horizontal(shoulders.point[1] - shoulders.point[0]);
  const double min_lead_m = 0.03;  // a shorter lead says nothing
  Vector3d forward = Vector3d::Zero();
  for (int side = 0; side < 2; ++side) {
    const Consensus heel = place(kLeftHeel, side), toe = place(kLeftToe, side);
    if (heel.count && toe.count) forward += Horizontal(toe.point[0] - heel.point[0]);
  }
  if (forward.norm() < min_lead_m) {
    forward = Vector3d::Zero();
    const Consensus nose = place(kNose, 0);
    const Vector3d across = a_to_b.normalized();
    const Vector3d ahead = Horizontal(nose.point[0] - 0.5 * (shoulders.point[0] + shoulders.point[1]));
    if (nose.count && (ahead - ahead.dot(across) * across).norm() >= min_lead_m)
      forward = ahead - ahead.dot(across) * across;
  }
  bool a_is_left;
  if (forward.norm() > 0) {
    a_is_left = a_to_b.dot(forward.cross(up)) > 0;  // B lies to the right of the front
  } else {  // no front seen: what most cameras call left
    int as_labelled = 0, settled = 0;
    for (int s : swap) {
      as_labelled += s == 0;
      settled += s >= 0;
    }
    a_is_left = 2 * as_labelled >= settled;
  }
  for (const JointPair& pair : kPairs) {
    for (int side = 0; side < 2; ++side) {
      const Consensus c = place(pair.left_landmark, side);
      if (!c.count) continue;
      const bool left = (side == 0) == a_is_left;
      const int joint = left ? pair.left_joint : pair.right_joint;
      out.position[joint] = c.point[0];
      out.cameras[joint] = c.count;
      out.rms_px[joint] = c.rms_px;
    }
  }
  for (int side = 0; side < 2; ++side) {
    const Consensus pinky = place(kLeftPinky, side), index = place(kLeftIndex, side);
    if (!pinky.count || !index.count) continue;
    const int hand = (side == 0) == a_is_left ? 0 : 1;
    out.knuckles[hand] = 0.5 * (pinky.point[0] + index.point[0]);
    out.knuckle_cameras[hand] = std::min(pinky.count, index.count);
  }
  return out;
}

}  // namespace confluent
