// Bundle adjustment for CalibrateRig: every camera's intrinsics and pose and every board pose,
// refined jointly on the corner reprojection error (Ceres, Huber loss). The Ceres cost functor
// (autodiff) lives only in this translation unit.

#include <ceres/ceres.h>

#include <set>

#include "calib/calibrate_internal.h"

namespace confluent {
namespace calibrate_internal {

namespace {

struct CornerResidual {
  CornerResidual(const Eigen::Vector3d& point_in_board, const Eigen::Vector2d& observed_px)
      : point_(point_in_board), observed_(observed_px) {}
  template <typename T>
  bool operator()(const T* intrinsics, const T* cam_from_world, const T* world_from_board, T* residual) const {
    const T point[3] = {T(point_.x()), T(point_.y()), T(point_.z())};
    T pixel[2];
    ProjectBoardPoint(intrinsics, cam_from_world, world_from_board, point, pixel);
    residual[0] = pixel[0] - T(observed_.x());
    residual[1] = pixel[1] - T(observed_.y());
    return true;
  }
  Eigen::Vector3d point_;
  Eigen::Vector2d observed_;
};

}  // namespace

AdjustmentResult Adjust(const CheckerboardSpec& board, const CalibrateOptions& options,
                        const std::vector<Observation>& observations, std::vector<CameraState>* cameras,
                        std::vector<std::array<double, 6>>* camera_blocks, std::map<int, std::array<double, 6>>* boards,
                        bool solve) {
  const std::vector<Eigen::Vector3d> points = board.CornersInBoard();
  ceres::HuberLoss loss(options.huber_px);  // shared by every residual block
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::set<int> used_cameras;
  for (const Observation& o : observations) {
    CameraState& camera = (*cameras)[o.camera];
    const ViewState& view = camera.views[o.view];
    for (std::size_t k = 0; k < points.size(); ++k) {
      auto* cost = new ceres::AutoDiffCostFunction<CornerResidual, 2, 9, 6, 6>(new CornerResidual(points[k], view.corners[k]));
      problem.AddResidualBlock(cost, &loss, camera.intrinsics,
                               (*camera_blocks)[o.camera].data(), (*boards)[o.frame].data());
    }
    used_cameras.insert(o.camera);
  }
  for (int c : used_cameras) {
    CameraState& camera = (*cameras)[c];
    if (c == options.reference_camera) problem.SetParameterBlockConstant((*camera_blocks)[c].data());
    if ((camera.known_intrinsics && !options.refine_known_intrinsics) || camera.reduced_model) {
      problem.SetParameterBlockConstant(camera.intrinsics);
    } else {
      std::vector<int> fixed;
      if (!options.estimate_tangential) {
        fixed.push_back(6);
        fixed.push_back(7);
      }
      if (!options.estimate_k3) fixed.push_back(8);
      if (!fixed.empty()) problem.SetManifold(camera.intrinsics, new ceres::SubsetManifold(9, fixed));
    }
  }
  AdjustmentResult result;
  auto rms = [&]() {
    double sum = 0.0;
    std::size_t count = 0;
    for (const Observation& o : observations) {
      const CameraState& camera = (*cameras)[o.camera];
      const ViewState& view = camera.views[o.view];
      for (std::size_t k = 0; k < points.size(); ++k) {
        double pixel[2];
        ProjectBoardPoint(camera.intrinsics, (*camera_blocks)[o.camera].data(), (*boards)[o.frame].data(),
                          points[k].data(), pixel);
        sum += (Eigen::Vector2d(pixel[0], pixel[1]) - view.corners[k]).squaredNorm();
        ++count;
      }
    }
    return count ? std::sqrt(sum / count) : 0.0;
  };
  result.initial_rms = rms();
  if (solve && !observations.empty()) {
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.num_threads = options.num_threads;
    solver_options.function_tolerance = 1e-12;
    solver_options.gradient_tolerance = 1e-14;
    solver_options.parameter_tolerance = 1e-12;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary solver_summary;
    ceres::Solve(solver_options, &problem, &solver_summary);
    result.iterations = static_cast<int>(solver_summary.iterations.size());
    result.converged = solver_summary.termination_type == ceres::CONVERGENCE;
  }
  result.final_rms = rms();
  return result;
}

}  // namespace calibrate_internal
}  // namespace confluent
