#include "refine/silhouette_refinement.h"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "calib/rig_check.h"
#include "core/error.h"
#include "core/mesh_ops.h"
#include "core/parallel.h"
#include "core/mesh_validation.h"
#include "refine/normalised_diffusion.h"
#include "silhouette/overlap.h"
#include "silhouette/rim_silhouette.h"

namespace confluent {

void SilhouetteRefinementOptions::Check() const {
  const std::string owner = "SilhouetteRefinementOptions.";
  RequireOption(iterations >= 0, owner + "iterations", iterations, ">= 0");
  RequireOption(search_px > 0.0, owner + "search_px", search_px, "> 0");
  RequireOption(max_rim_cosine > 0.0 && max_rim_cosine < 1.0, owner + "max_rim_cosine", max_rim_cosine, "in (0, 1)");
  RequireOption(spread_stiffness > 0.0, owner + "spread_stiffness", spread_stiffness, "> 0");
  RequireOption(fade_weight > 0.0, owner + "fade_weight", fade_weight, "> 0");
  RequireOption(step_gain > 0.0, owner + "step_gain", step_gain, "> 0");
  RequireOption(threads >= 1, owner + "threads", threads, ">= 1");
}

namespace {

bool Inside(const Image& mask, const Eigen::Vector2d& pixel) {
  if (!(pixel.x() >= -0.5 && pixel.y() >= -0.5)) return false;
  const int x = static_cast<int>(pixel.x() + 0.5), y = static_cast<int>(pixel.y() + 0.5);  // nearest pixel
  if (x >= mask.width || y >= mask.height) return false;
  return mask.data[static_cast<std::size_t>(y) * mask.width + x] > 127;
}

}  // namespace

struct SilhouetteRefiner::Impl {
  SilhouetteRefinementOptions options;
  RowMatrixX3i faces;
  std::unique_ptr<NormalisedDiffusion> spread;  // of the rim steps over the surface
  bool closed = false;    // watertight: the fast facing-triangle raster gives the silhouette
  std::unique_ptr<RimSilhouetteRasterizer> rim;  // faster still, when the scan is closed and oriented

  // Sums, per vertex, the 3D steps that bring it onto `mask`'s edge where it lies on the outline
  // of `mesh` in `camera` (`own` is that outline's silhouette).
  void RimSteps(const Mesh& mesh, const RowMatrixX3d& normals, const Camera& camera, const Image& own,
                const Image& mask, RowMatrixX3d* step_sum, std::vector<int>* count) const {
    const Eigen::Vector3d centre = camera.center_in_world();
    const double half = 0.5, reach = options.search_px;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Eigen::Vector3d point = mesh.vertices.row(v).transpose(), normal = normals.row(v).transpose();
      if (std::abs(normal.dot((point - centre).normalized())) > options.max_rim_cosine) continue;
      Eigen::Vector2d pixel;
      if (!camera.ProjectChecked(point, &pixel)) continue;
      bool in = false, out = false;  // on the outline: both sides within one pixel
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) (Inside(own, pixel + Eigen::Vector2d(dx, dy)) ? in : out) = true;
      if (!in || !out) continue;
      Eigen::Vector2d outward = camera.Project(point + 0.01 * normal) - pixel;
      if (!(outward.norm() > 1e-9)) continue;
      outward.normalize();
      if (Inside(own, pixel + 2.0 * outward) && !Inside(own, pixel - 2.0 * outward)) outward = -outward;
      // The edges (inside, then outside, going outwards) of the mask and of the scan's own
      // silhouette nearest to the vertex, found alike so that their sampling biases cancel.
      auto nearest_edge = [&](const Image& image, double limit) {
        for (double d = 0.0; d <= limit; d += half)  // t = d and t = -d - half are equally near
          for (const double t : {d, -d - half})
            if (Inside(image, pixel + t * outward) && !Inside(image, pixel + (t + half) * outward)) return t + 0.5 * half;
        return limit + 1.0;
      };
      const double own_edge = nearest_edge(own, 1.5);
      if (std::abs(own_edge) > 1.5) continue;
      const double mask_edge = nearest_edge(mask, reach);
      if (std::abs(mask_edge) > reach) continue;
      const double best = mask_edge - own_edge;
      // The same pixel shift at the vertex's depth, perpendicular to its ray.
      const Eigen::Vector3d in_camera = camera.rotation * point + camera.translation;
      const Eigen::Vector3d step_in_camera(best * outward.x() * in_camera.z() / camera.K(0, 0),
                                           best * outward.y() * in_camera.z() / camera.K(1, 1), 0.0);
      step_sum->row(v) += (camera.rotation.transpose() * step_in_camera).transpose();
      ++(*count)[v];
    }
  }
};

SilhouetteRefiner::SilhouetteRefiner(const Mesh& scan, const SilhouetteRefinementOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  impl_->faces = scan.faces;
  impl_->closed = ValidateMesh(scan).is_watertight();
  impl_->rim = std::make_unique<RimSilhouetteRasterizer>(scan.faces);
  if (scan.num_faces() == 0) throw InputError("scan", "silhouette refinement: the scan has no faces");
  impl_->spread = std::make_unique<NormalisedDiffusion>(scan, options.spread_stiffness, "scan");
  impl_->spread->set_threads(options.threads);
}

SilhouetteRefiner::~SilhouetteRefiner() = default;
SilhouetteRefiner::SilhouetteRefiner(SilhouetteRefiner&&) noexcept = default;
SilhouetteRefiner& SilhouetteRefiner::operator=(SilhouetteRefiner&&) noexcept = default;

RowMatrixX3d SilhouetteRefiner::Refine(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                                       const std::vector<Image>& masks, SilhouetteRefinementSummary* summary_out,
                                       int iterations) const {
  const Impl& s = *impl_;
  const int n = static_cast<int>(vertices.rows());
  if (n != s.spread->num_vertices()) throw std::invalid_argument("Refine: the vertex count differs from the scan's");
  if (cameras.size() != masks.size()) throw std::invalid_argument("Refine: one mask per camera is needed");
  std::vector<int> usable;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    if (masks[c].width != cameras[c].width || masks[c].height != cameras[c].height || masks[c].channels != 1)
      throw std::invalid_argument("Refine: mask " + std::to_string(c) + " does not match camera " + cameras[c].name);
    if (CountForeground(masks[c]) > 0) usable.push_back(static_cast<int>(c));
  }
  SilhouetteRefinementSummary summary;
  summary.iou_before.assign(cameras.size(), NAN);
  summary.iou_after.assign(cameras.size(), NAN);
  Mesh mesh;
  mesh.vertices = vertices;
  mesh.faces = s.faces;
  if (!vertices.allFinite()) throw std::invalid_argument("Refine: non-finite vertices");
  const RowMatrixX3d start = vertices;
  // The scan's own silhouette: the rim fill when the scan is closed and consistently oriented,
  // else the facing-triangle fill when it is watertight.
  auto silhouette = [&s](const Mesh& posed, const Camera& camera) {
    if (s.rim->closed()) return s.rim->Rasterize(posed.vertices, camera);
    return s.closed ? RasterizeClosedMesh(posed, camera) : RasterizeSilhouette(posed, camera);
  };
  const int threads = std::max(1, std::min<int>(s.options.threads, static_cast<int>(usable.size())));
  // Mean IoU over the usable cameras.
  auto mean_over_usable = [&usable](const std::vector<double>& iou) {
    double sum = 0.0;
    for (int c : usable) sum += iou[c];
    return usable.empty() ? 0.0 : sum / usable.size();
  };
  // Each move is the spread rim steps times `gain`. A move after which the mean IoU drops is
  // replaced by half of it, and the gain halved (a backtracking line search).
  double gain = s.options.step_gain;
  RowMatrixX3d before_move = mesh.vertices, move = RowMatrixX3d::Zero(n, 3);
  std::vector<double> iou(cameras.size(), NAN), iou_before_move = iou;
  double mean_iou_before_move = -1.0;
  const int rounds = iterations >= 0 ? iterations : s.options.iterations;
  for (int round = 0; round < rounds && !usable.empty(); ++round) {
    const RowMatrixX3d normals = VertexNormals(mesh);
    std::vector<RowMatrixX3d> step_sums(threads, RowMatrixX3d::Zero(n, 3));
    std::vector<std::vector<int>> counts(threads, std::vector<int>(n, 0));
    auto work = [&](int part) {
      for (std::size_t i = part; i < usable.size(); i += threads) {
        const int c = usable[i];
        const Image own = silhouette(mesh, cameras[c]);
        iou[c] = MaskIoU(own, masks[c]);
        s.RimSteps(mesh, normals, cameras[c], own, masks[c], &step_sums[part], &counts[part]);
      }
    };
    ParallelFor(threads, threads, work);
    if (round == 0) summary.iou_before = iou;
    const double mean_iou = mean_over_usable(iou);
    if (mean_iou < mean_iou_before_move) {
      gain *= 0.5;
      mesh.vertices = before_move + gain * move;
      continue;
    }
    // Normalised diffusion of the mean rim steps.
    Eigen::MatrixXd mean_steps = Eigen::MatrixXd::Zero(n, 3);
    std::vector<bool> on_rim(n, false);
    summary.rim_vertices = 0;
    for (int v = 0; v < n; ++v) {
      int count = 0;
      Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
      for (int part = 0; part < threads; ++part) count += counts[part][v], sum += step_sums[part].row(v);
      if (count == 0) continue;
      mean_steps.row(v) = sum / count;
      on_rim[v] = true;
      ++summary.rim_vertices;
    }
    move = s.spread->Spread(mean_steps, on_rim, s.options.fade_weight);
    before_move = mesh.vertices;
    iou_before_move = iou;
    mean_iou_before_move = mean_iou;
    mesh.vertices += gain * move;
  }
  for (int c : usable) iou[c] = MaskIoU(silhouette(mesh, cameras[c]), masks[c]);
  if (!usable.empty() && mean_over_usable(iou) < mean_iou_before_move) {  // the last move made it worse
    mesh.vertices = before_move;
    iou = iou_before_move;
  }
  if (rounds == 0) summary.iou_before = iou;  // no round measured it
  summary.iou_after = iou;
  const Eigen::VectorXd shift = (mesh.vertices - start).rowwise().norm();
  summary.mean_shift_m = n ? shift.mean() : 0.0;
  summary.max_shift_m = n ? shift.maxCoeff() : 0.0;
  if (summary_out) *summary_out = std::move(summary);
  return mesh.vertices;
}

}  // namespace confluent
