#pragma once
// Skeletal skinning of a rest-pose mesh: linear blend and dual-quaternion blend (Kavan et al.
// 2007), with at most four joint influences per vertex.

#include <Eigen/Core>

#include "core/mesh.h"
#include "core/skeleton.h"

namespace confluent {

// Per-vertex joint influences. Row i lists up to 4 joints (index into Skeleton::joints, -1 for
// an unused slot) and their weights (>= 0, summing to 1 over the used slots).
struct SkinWeights {
  static constexpr int kMaxInfluences = 4;
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> joints;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> weights;

  int num_vertices() const { return static_cast<int>(joints.rows()); }
  // Throws InputError(`source`) when the sizes differ, a joint index is outside
  // [-1, num_joints), a weight is negative/non-finite, or a row's weights do not sum to 1
  // (to 1e-6).
  void Check(int num_joints, const std::string& source = {}) const;
};

// How the joint transforms are blended.
enum class SkinningMethod {
  kLinear,          // linear blend skinning (matrix palette)
  kDualQuaternion,  // dual-quaternion skinning: no candy-wrapper collapse at twisted joints
};

// The per-joint skinning transforms world_from_joint(pose) * world_from_joint(rest)^-1: they map
// a rest-pose point rigidly attached to the joint to its posed position.
std::vector<Eigen::Isometry3d> SkinningTransforms(const Skeleton& skeleton, const Pose& pose);

// Poses `rest_vertices` (n x 3, world frame of the rest pose, metres) with `weights`.
// At the rest pose the result equals the input to rounding. Aborts (assert) on size mismatch;
// validate external weights with SkinWeights::Check first.
RowMatrixX3d SkinVertices(const RowMatrixX3d& rest_vertices, const SkinWeights& weights,
                          const Skeleton& skeleton, const Pose& pose,
                          SkinningMethod method = SkinningMethod::kDualQuaternion);

}  // namespace confluent
