#include "studio/motion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "core/error.h"

namespace confluent {
namespace {

using Eigen::Vector3d;

// One keyframe: time, root yaw (degrees about +z) and per-joint angles in degrees.
// For most joints the angles are (about x, about y, about z) of the parent frame, composed as
// Rz * Ry * Rx. Elbows use x as a hinge angle (flexion, forearm towards the front).
struct Key {
  double time_s;
  double yaw_deg;
  std::map<std::string, Vector3d> angles;
};

// Shoulder abduction that raises the arm sideways: about +y for the left arm (at -x), -y for
// the right. Flexion raises it forwards (about +x).
Vector3d Shoulder(bool left, double abduction_deg, double flexion_deg = 0.0, double twist_deg = 0.0) {
  return Vector3d(flexion_deg, left ? abduction_deg : -abduction_deg, left ? -twist_deg : twist_deg);
}

std::vector<Key> Keys() {
  auto arms = [](double abduction, double flexion_left, double flexion_right, double elbow) {
    return std::map<std::string, Vector3d>{
        {"left_shoulder", Shoulder(true, abduction, flexion_left)},
        {"right_shoulder", Shoulder(false, abduction, flexion_right)},
        {"left_elbow", Vector3d(elbow, 0, 0)},
        {"right_elbow", Vector3d(elbow, 0, 0)}};
  };
  auto merge = [](std::map<std::string, Vector3d> a, const std::map<std::string, Vector3d>& b) {
    for (const auto& [k, v] : b) a[k] = v;
    return a;
  };
  std::vector<Key> keys;
  keys.push_back({0.0, 0.0, arms(0, 0, 0, 10)});
  // Arms over the head, looking up.
  keys.push_back({0.55, 0.0, merge(arms(135, 0, 0, 15), {{"spine", Vector3d(6, 0, 0)}, {"head", Vector3d(12, 0, 0)}})});
  // Arms out sideways.
  keys.push_back({0.95, 0.0, merge(arms(55, 0, 0, 5), {{"chest", Vector3d(0, 0, 15)}})});
  // A full turn with swinging arms.
  keys.push_back({1.55, 180.0,
                  merge(arms(50, 45, -35, 25), {{"spine", Vector3d(-5, 8, 0)}, {"chest", Vector3d(0, 0, -20)},
                                                 {"left_hip", Vector3d(20, 0, 0)}, {"left_knee", Vector3d(-30, 0, 0)}})});
  keys.push_back({2.15, 360.0, merge(arms(30, -20, 30, 40), {{"chest", Vector3d(0, 0, 10)}})});
  // Kick with the right leg, arms out for balance.
  keys.push_back({2.45, 360.0,
                  merge(arms(35, 20, 20, 30), {{"right_hip", Vector3d(-25, 0, 0)}, {"right_knee", Vector3d(-50, 0, 0)},
                                                {"left_knee", Vector3d(-12, 0, 0)}})});
  keys.push_back({2.75, 360.0,
                  merge(arms(70, -25, 10, 15), {{"right_hip", Vector3d(85, 0, 0)}, {"right_knee", Vector3d(-8, 0, 0)},
                                                {"right_ankle", Vector3d(-25, 0, 0)}, {"left_knee", Vector3d(-15, 0, 0)},
                                                {"spine", Vector3d(12, 0, 0)}, {"chest", Vector3d(4, 0, 0)}})});
  keys.push_back({3.05, 360.0, merge(arms(15, 0, 0, 20), {{"head", Vector3d(-10, 0, 20)}})});
  // Crouch with the arms forward.
  keys.push_back({3.55, 360.0,
                  merge(arms(10, 75, 70, 35),
                        {{"left_hip", Vector3d(100, 0, 0)}, {"right_hip", Vector3d(100, 0, 0)},
                         {"left_knee", Vector3d(-125, 0, 0)}, {"right_knee", Vector3d(-125, 0, 0)},
                         {"left_ankle", Vector3d(30, 0, 0)}, {"right_ankle", Vector3d(30, 0, 0)},
                         {"spine", Vector3d(-25, 0, 0)}, {"chest", Vector3d(-8, 0, 0)}, {"head", Vector3d(25, 0, 0)}})});
  keys.push_back({4.0, 360.0, arms(0, 0, 0, 10)});
  return keys;
}

// Cubic Hermite interpolation of per-key values with Catmull-Rom tangents (zero at the ends).
template <typename Get>
double Spline(const std::vector<Key>& keys, double t, Get get) {
  if (t <= keys.front().time_s) return get(keys.front());
  if (t >= keys.back().time_s) return get(keys.back());
  std::size_t i = 0;
  while (keys[i + 1].time_s < t) ++i;
  const double t0 = keys[i].time_s, t1 = keys[i + 1].time_s, h = t1 - t0;
  auto tangent = [&](std::size_t k) {
    if (k == 0 || k + 1 == keys.size()) return 0.0;
    return (get(keys[k + 1]) - get(keys[k - 1])) / (keys[k + 1].time_s - keys[k - 1].time_s);
  };
  const double u = (t - t0) / h;
  const double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * get(keys[i]) + (u3 - 2 * u2 + u) * h * tangent(i) +
         (-2 * u3 + 3 * u2) * get(keys[i + 1]) + (u3 - u2) * h * tangent(i + 1);
}

Eigen::Quaterniond EulerZYX(const Vector3d& deg) {
  const Vector3d r = deg * M_PI / 180.0;
  return Eigen::Quaterniond(Eigen::AngleAxisd(r.z(), Vector3d::UnitZ()) * Eigen::AngleAxisd(r.y(), Vector3d::UnitY()) *
                            Eigen::AngleAxisd(r.x(), Vector3d::UnitX()));
}

}  // namespace

void StudioMotionOptions::Check() const {
  const std::string owner = "StudioMotionOptions.";
  RequireOption(num_frames >= 1, owner + "num_frames", num_frames, ">= 1");
  RequireOption(fps > 0.0 && std::isfinite(fps), owner + "fps", fps, "> 0 and finite");
  RequireOption(speed > 0.0 && std::isfinite(speed), owner + "speed", speed, "> 0 and finite");
  RequireOption(bvh_start_s >= 0.0 && std::isfinite(bvh_start_s), owner + "bvh_start_s", bvh_start_s,
                ">= 0 seconds and finite");
}

double DefaultPerformanceDuration() { return Keys().back().time_s; }

std::vector<Pose> DefaultPerformance(const Skeleton& skeleton, const StudioMotionOptions& options) {
  options.Check();
  const std::vector<Key> keys = Keys();
  std::vector<std::string> animated;
  for (const auto& key : keys)
    for (const auto& entry : key.angles)
      if (std::find(animated.begin(), animated.end(), entry.first) == animated.end()) animated.push_back(entry.first);
  for (const char* name : {"pelvis", "left_elbow", "right_elbow", "left_ankle", "right_ankle", "left_toe", "right_toe"})
    if (skeleton.IndexOf(name) < 0)
      throw UsageError(std::string("default performance: the skeleton has no joint '") + name + "'");
  for (const auto& name : animated)
    if (skeleton.IndexOf(name) < 0)
      throw UsageError("default performance: the skeleton has no joint '" + name + "'");
  const std::vector<Vector3d> rest = skeleton.RestPositions();
  const int root = 0;
  std::vector<Pose> poses;
  for (int f = 0; f < options.num_frames; ++f) {
    const double t = f / options.fps * options.speed;
    Pose pose = Pose::Rest(skeleton.size());
    const double yaw = Spline(keys, t, [](const Key& k) { return k.yaw_deg; });
    pose.local_rotations[root] = Eigen::Quaterniond(Eigen::AngleAxisd(yaw * M_PI / 180.0, Vector3d::UnitZ()));
    for (const auto& name : animated) {
      Vector3d angles;
      for (int c = 0; c < 3; ++c)
        angles(c) = Spline(keys, t, [&](const Key& k) {
          const auto it = k.angles.find(name);
          return it == k.angles.end() ? 0.0 : it->second(c);
        });
      const int joint = skeleton.IndexOf(name);
      if (name == "left_elbow" || name == "right_elbow") {
        // Hinge about (upper arm direction) x (+y): flexion swings the forearm forwards.
        const int parent = skeleton.joints[joint].parent;
        const Vector3d dir = (rest[joint] - rest[parent]).normalized();
        const Vector3d hinge = dir.cross(Vector3d::UnitY()).normalized();
        pose.local_rotations[joint] = Eigen::Quaterniond(Eigen::AngleAxisd(angles.x() * M_PI / 180.0, hinge));
      } else {
        pose.local_rotations[joint] = EulerZYX(angles);
      }
    }
    // Keep the lowest foot point on the floor: shift the root vertically.
    const std::vector<Vector3d> positions = JointPositions(skeleton, pose);
    double lowest = 1e9;
    for (const char* name : {"left_ankle", "right_ankle", "left_toe", "right_toe"}) {
      const int j = skeleton.IndexOf(name);
      lowest = std::min(lowest, positions[j].z() - rest[j].z());
    }
    pose.root_translation.z() -= lowest;
    poses.push_back(pose);
  }
  return poses;
}

std::vector<Pose> BvhPerformance(const Skeleton& skeleton, const StudioMotionOptions& options,
                                 BvhRetargetResult* retarget) {
  options.Check();
  if (options.bvh_path.empty()) throw UsageError("bvh performance: no BVH file given");
  BvhRetargetResult result = RetargetBvhFile(options.bvh_path, skeleton, options.bvh);
  std::vector<Pose> poses =
      SampleRetargetedMotion(result, options.fps, options.speed, options.num_frames, options.bvh_start_s);
  if (retarget) {
    result.poses.clear();
    *retarget = std::move(result);
  }
  return poses;
}

PerformancePlacement KeepPerformanceInVolume(std::vector<Pose>* poses, const Skeleton& skeleton,
                                             const Eigen::Vector2d& centre, double volume_radius_m, double fps,
                                             bool in_place, const std::string& source) {
  PerformancePlacement placement;
  if (poses->empty()) return placement;
  const Eigen::Vector2d pelvis_rest = skeleton.joints[0].offset_in_parent.head<2>();
  auto pelvis = [&](const Pose& pose) -> Eigen::Vector2d { return pelvis_rest + pose.root_translation.head<2>(); };
  // Centres the path's bounding box on `centre`; returns the largest distance from it.
  auto centre_path = [&]() {
    Eigen::Vector2d lo = pelvis((*poses)[0]), hi = lo;
    for (const Pose& pose : *poses) lo = lo.cwiseMin(pelvis(pose)), hi = hi.cwiseMax(pelvis(pose));
    const Eigen::Vector2d shift = centre - 0.5 * (lo + hi);
    double farthest = 0.0;
    for (Pose& pose : *poses) {
      pose.root_translation.head<2>() += shift;
      farthest = std::max(farthest, (pelvis(pose) - centre).norm());
    }
    return farthest;
  };
  placement.travel_m = centre_path();
  placement.radius_m = placement.travel_m;
  if (in_place) {
    // The slow path: a sliding mean over 1 s, the path continued past its ends by point
    // reflection (so that steady travel at the ends is removed too, not left half-averaged).
    const int n = static_cast<int>(poses->size());
    const int half = std::max(1, static_cast<int>(std::lround(0.5 * fps)));
    auto path = [&](int k) -> Eigen::Vector2d {
      if (k < 0) return 2 * pelvis((*poses)[0]) - pelvis((*poses)[std::min(-k, n - 1)]);
      if (k >= n) return 2 * pelvis((*poses)[n - 1]) - pelvis((*poses)[std::max(2 * (n - 1) - k, 0)]);
      return pelvis((*poses)[k]);
    };
    std::vector<Eigen::Vector2d> slow(n);
    for (int f = 0; f < n; ++f) {
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      for (int k = f - half; k <= f + half; ++k) sum += path(k);
      slow[f] = sum / (2 * half + 1);
    }
    for (int f = 0; f < n; ++f) (*poses)[f].root_translation.head<2>() -= slow[f] - slow[0];
    placement.made_in_place = true;
    placement.radius_m = centre_path();
  }
  if (placement.radius_m > volume_radius_m) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "the performer's pelvis travels %.2f m from the centre of its path%s, and the cameras see a "
                  "performer whole only within %.2f m of the studio's centre: choose a shorter excerpt (--frames, "
                  "--bvh-start)%s",
                  placement.radius_m, in_place ? " even performed on the spot" : "", volume_radius_m,
                  in_place ? "" : " or perform it on the spot (--bvh-in-place)");
    throw InputError(source, text);
  }
  return placement;
}

std::vector<Pose> StudioPerformance(const Skeleton& skeleton, const StudioMotionOptions& options) {
  return options.bvh_path.empty() ? DefaultPerformance(skeleton, options) : BvhPerformance(skeleton, options);
}

}  // namespace confluent
