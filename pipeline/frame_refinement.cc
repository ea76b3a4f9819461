#include "pipeline/frame_refinement.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "pipeline/run_folder.h"

namespace confluent {

void FrameRefinementOptions::Check() const {
  const std::string owner = "FrameRefinementOptions.";
  RequireOption(silhouette_rounds >= 0, owner + "silhouette_rounds", silhouette_rounds, ">= 0");
  RequireOption(photo_rounds >= 0, owner + "photo_rounds", photo_rounds, ">= 0");
  RequireOption(photo_full_resolution_rounds >= 0, owner + "photo_full_resolution_rounds", photo_full_resolution_rounds,
                ">= 0");
  RequireOption(outline_rounds >= 0, owner + "outline_rounds", outline_rounds, ">= 0");
  RequireOption(keyframe_interval >= 1, owner + "keyframe_interval", keyframe_interval, ">= 1");
  RequireOption(carried_silhouette_rounds >= 0, owner + "carried_silhouette_rounds", carried_silhouette_rounds, ">= 0");
  RequireOption(carried_photo_rounds >= 0, owner + "carried_photo_rounds", carried_photo_rounds, ">= 0");
  RequireOption(threads >= 1, owner + "threads", threads, ">= 1");
}

namespace {

SilhouetteRefinementOptions SilhouetteOptions(const FrameRefinementOptions& options) {
  options.Check();
  SilhouetteRefinementOptions silhouette;
  silhouette.threads = options.threads;
  silhouette.iterations = options.silhouette_rounds;
  return silhouette;
}

PhotoRefinementOptions PhotoOptions(const FrameRefinementOptions& options) {
  PhotoRefinementOptions photo;
  photo.threads = options.threads;
  photo.rounds = options.photo_rounds;
  photo.full_resolution_rounds = options.photo_full_resolution_rounds;
  return photo;
}

// Per vertex, one neighbour: the next corner of the first face that uses it (-1: unused vertex).
std::vector<int> FirstNeighbours(const RowMatrixX3i& faces, int num_vertices) {
  std::vector<int> neighbour(num_vertices, -1);
  for (int f = faces.rows() - 1; f >= 0; --f)
    for (int k = 0; k < 3; ++k) neighbour[faces(f, k)] = faces(f, (k + 1) % 3);
  return neighbour;
}

// Per vertex, an orthonormal frame that turns with the surface: the tangent towards its
// neighbour, the bitangent and the normal (rows 3v, 3v+1, 3v+2 of the result).
RowMatrixX3d LocalFrames(const Mesh& mesh, const std::vector<int>& neighbour) {
  const RowMatrixX3d normals = VertexNormals(mesh);
  RowMatrixX3d frames(3 * mesh.num_vertices(), 3);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::RowVector3d n = normals.row(v);
    Eigen::RowVector3d t = neighbour[v] >= 0 ? Eigen::RowVector3d(mesh.vertices.row(neighbour[v]) - mesh.vertices.row(v))
                                             : Eigen::RowVector3d::UnitX();
    t -= t.dot(n) * n;
    if (!(t.norm() > 1e-12)) {  // the neighbour lies along the normal (a degenerate face)
      const Eigen::RowVector3d axis = std::abs(n.x()) < 0.9 ? Eigen::RowVector3d::UnitX() : Eigen::RowVector3d::UnitY();
      t = axis - axis.dot(n) * n;
    }
    t.normalize();
    frames.row(3 * v) = t;
    frames.row(3 * v + 1) = n.cross(t);
    frames.row(3 * v + 2) = n;
  }
  return frames;
}

}  // namespace

FrameRefinement::FrameRefinement(const Mesh& scan, const std::vector<Camera>& cameras,
                                 const FrameRefinementOptions& options)
    : options_(options),
      faces_(scan.faces),
      neighbours_(FirstNeighbours(scan.faces, scan.num_vertices())),
      cameras_(cameras),
      silhouette_(scan, SilhouetteOptions(options)),
      photo_(scan, PhotoOptions(options)) {}

RowMatrixX3d FrameRefinement::Refine(int frame, const RowMatrixX3d& deformed, const std::vector<Image>& masks,
                                     const std::vector<Image>& images, FrameRefinementSummary* summary_out) {
  FrameRefinementSummary summary;
  const bool carry = !IsKeyframe(frame) && carried_frame_ == frame - 1;
  Mesh deformed_mesh;
  deformed_mesh.vertices = deformed;
  deformed_mesh.faces = faces_;
  // The local frames, only where a correction is carried in or out.
  const bool carried_on = !IsKeyframe(frame + 1);
  const RowMatrixX3d frames = carry || carried_on ? LocalFrames(deformed_mesh, neighbours_) : RowMatrixX3d();
  RowMatrixX3d current = deformed;
  if (carry) {
    for (int v = 0; v < deformed.rows(); ++v)
      current.row(v) += carried_(v, 0) * frames.row(3 * v) + carried_(v, 1) * frames.row(3 * v + 1) +
                        carried_(v, 2) * frames.row(3 * v + 2);
  }
  summary.carried = carry;

  double start = NowSeconds();
  SilhouetteRefinementSummary silhouette;
  current = silhouette_.Refine(current, cameras_, masks, &silhouette,
                               carry ? options_.carried_silhouette_rounds : options_.silhouette_rounds);
  summary.iou_start = silhouette.iou_before;
  summary.iou_after = silhouette.iou_after;
  summary.silhouette_seconds = NowSeconds() - start;
  if (options_.photo) {
    start = NowSeconds();
    current = photo_.Refine(current, cameras_, images, &summary.photo,
                            carry ? options_.carried_photo_rounds : options_.photo_rounds);
    SilhouetteRefinementSummary outline;
    current = silhouette_.Refine(current, cameras_, masks, &outline, options_.outline_rounds);
    summary.iou_after = outline.iou_after;
    summary.photo_seconds = NowSeconds() - start;
  }
  if (carried_on) {
    carried_.resize(deformed.rows(), 3);
    for (int v = 0; v < deformed.rows(); ++v) {
      const Eigen::RowVector3d correction = current.row(v) - deformed.row(v);
      carried_.row(v) << correction.dot(frames.row(3 * v)), correction.dot(frames.row(3 * v + 1)),
          correction.dot(frames.row(3 * v + 2));
    }
  }
  carried_frame_ = carried_on ? frame : -2;
  if (summary_out) *summary_out = std::move(summary);
  return current;
}

}  // namespace confluent
