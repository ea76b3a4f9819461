#include "refine/photo_refinement.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>
#include <functional>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "core/parallel.h"
#include "refine/normalised_diffusion.h"
#include "render/cpu_raster.h"

namespace confluent {

void PhotoRefinementOptions::Check() const {
  const std::string owner = "PhotoRefinementOptions.";
  RequireOption(rounds >= 0, owner + "rounds", rounds, ">= 0");
  RequireOption(neighbours >= 1, owner + "neighbours", neighbours, ">= 1");
  RequireOption(step_gain > 0.0, owner + "step_gain", step_gain, "> 0");
  RequireOption(spread_stiffness > 0.0, owner + "spread_stiffness", spread_stiffness, "> 0");
  RequireOption(fade_weight > 0.0, owner + "fade_weight", fade_weight, "> 0");
  RequireOption(min_view_cosine >= 0.0 && min_view_cosine < 1.0, owner + "min_view_cosine", min_view_cosine, "in [0, 1)");
  RequireOption(max_flow_px > 0.0, owner + "max_flow_px", max_flow_px, "> 0");
  RequireOption(max_ray_gap_m > 0.0, owner + "max_ray_gap_m", max_ray_gap_m, "> 0");
  RequireOption(max_offset_m > 0.0, owner + "max_offset_m", max_offset_m, "> 0");
  RequireOption(visibility_tolerance_m > 0.0, owner + "visibility_tolerance_m", visibility_tolerance_m, "> 0");
  RequireOption(outline_margin_px >= 0, owner + "outline_margin_px", outline_margin_px, ">= 0");
  RequireOption(flow_finest_scale >= 0, owner + "flow_finest_scale", flow_finest_scale, ">= 0");
  RequireOption(full_resolution_rounds >= 0, owner + "full_resolution_rounds", full_resolution_rounds, ">= 0");
  RequireOption(full_resolution_spread_stiffness > 0.0, owner + "full_resolution_spread_stiffness",
                full_resolution_spread_stiffness, "> 0");
  RequireOption(full_resolution_patch_stride >= 1, owner + "full_resolution_patch_stride", full_resolution_patch_stride,
                ">= 1");
  RequireOption(flow_variational_iterations >= 0, owner + "flow_variational_iterations", flow_variational_iterations, ">= 0");
  RequireOption(full_resolution_variational_iterations >= 0, owner + "full_resolution_variational_iterations",
                full_resolution_variational_iterations, ">= 0");
  RequireOption(threads >= 1, owner + "threads", threads, ">= 1");
}

namespace {

// One camera in one round: its grey image on the ideal (distortion-free) pixel grid and the
// scan's depth map and face ids there.
struct View {
  const Camera* camera = nullptr;
  Eigen::Matrix3d K_inverse;
  Eigen::Vector3d centre;
  cv::Mat grey;                      // CV_8U, ideal pixels
  std::vector<float> inverse_depth;  // 1 / camera z, 0 where no surface
  std::vector<std::int32_t> face_ids;
  PixelBox box;                      // covers every drawn pixel
};

// Ideal pinhole projection (the depth maps and the grey images are distortion-free).
Eigen::Vector2d ProjectIdeal(const Camera& camera, const Eigen::Vector3d& point_in_camera) {
  const Eigen::Vector3d h = camera.K * (point_in_camera / point_in_camera.z());
  return h.head<2>();
}

// Closest points of two rays (origin + t direction); false when they are nearly parallel.
bool ClosestPoints(const Eigen::Vector3d& oa, const Eigen::Vector3d& ra, const Eigen::Vector3d& ob,
                   const Eigen::Vector3d& rb, Eigen::Vector3d* pa, Eigen::Vector3d* pb) {
  const Eigen::Vector3d w0 = oa - ob;
  const double a = ra.dot(ra), b = ra.dot(rb), c = rb.dot(rb), d = ra.dot(w0), e = rb.dot(w0);
  const double denominator = a * c - b * b;
  if (denominator < 1e-6 * a * c) return false;
  *pa = oa + ((b * e - c * d) / denominator) * ra;
  *pb = ob + ((a * e - b * d) / denominator) * rb;
  return true;
}

double Bilinear(const cv::Mat& grey, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  const uchar* r0 = grey.ptr<uchar>(y0);
  const uchar* r1 = grey.ptr<uchar>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// Per-vertex sums of the offsets that one thread measured.
struct OffsetSums {
  Eigen::VectorXd offset, weight;
  double flow_sum = 0.0;
  long long samples = 0;
  explicit OffsetSums(int n) : offset(Eigen::VectorXd::Zero(n)), weight(Eigen::VectorXd::Zero(n)) {}
};

}  // namespace

struct PhotoRefiner::Impl {
  PhotoRefinementOptions options;
  RowMatrixX3i faces;
  std::unique_ptr<NormalisedDiffusion> spread;       // the half-resolution rounds' offsets
  // The full-resolution rounds' offsets; null without such rounds or when the stiffnesses agree.
  std::unique_ptr<NormalisedDiffusion> fine_spread;
  std::unique_ptr<CpuRasterizer> rasterizer;

  // Camera `a` against neighbour `b`: b's image reprojected into a through the surface, the flow
  // from it to a's image (down to pyramid level `finest_scale`, with this many variational
  // refinement iterations), and per used pixel
  // the triangulated offset along the face normal.
  void MeasurePair(const View& a, const View& b, const RowMatrixX3d& face_normals, int finest_scale, int variational_iterations,
                   OffsetSums* sums) const {
    const Camera& ca = *a.camera;
    const Camera& cb = *b.camera;
    const int width = ca.width, height = ca.height;
    if (a.box.empty()) return;  // the scan is not in this camera's view
    const int margin = 16;
    const int x0 = std::max(0, a.box.x0 - margin), y0 = std::max(0, a.box.y0 - margin);
    const int x1 = std::min(width, a.box.x1 + margin), y1 = std::min(height, a.box.y1 + margin);
    if (x1 - x0 < 32 || y1 - y0 < 32) return;  // too small for the flow's pyramid
    const cv::Rect crop(x0, y0, x1 - x0, y1 - y0);
    // Pixels well inside the scan's outline in a.
    cv::Mat inner(crop.size(), CV_8U);
    for (int y = 0; y < crop.height; ++y)
      for (int x = 0; x < crop.width; ++x)
        inner.at<uchar>(y, x) = a.inverse_depth[static_cast<std::size_t>(y + crop.y) * width + x + crop.x] > 0 ? 255 : 0;
    if (options.outline_margin_px > 0)
      cv::erode(inner, inner, cv::Mat(), cv::Point(-1, -1), options.outline_margin_px);
    // A pixel of a whose surface point b sees: where b's colour was read.
    struct Sample {
      int x, y, face;           // in the crop
      Eigen::Vector3d point;    // the scan's surface point, world
      float b_x, b_y;           // its pixel in b
    };
    std::vector<Sample> samples;
    cv::Mat warped = a.grey(crop).clone(), real = a.grey(crop).clone();
    const double min_cos = options.min_view_cosine;
    for (int y = 0; y < crop.height; ++y)
      for (int x = 0; x < crop.width; ++x) {
        if (!inner.at<uchar>(y, x)) continue;
        const std::size_t index = static_cast<std::size_t>(y + crop.y) * width + x + crop.x;
        const int face = a.face_ids[index];
        if (face < 0) continue;
        const Eigen::Vector3d in_a = (a.K_inverse * Eigen::Vector3d(x + crop.x, y + crop.y, 1.0)) / a.inverse_depth[index];
        const Eigen::Vector3d point = ca.rotation.transpose() * (in_a - ca.translation);
        const Eigen::Vector3d normal = face_normals.row(face).transpose();
        if (std::abs(normal.dot((point - a.centre).normalized())) < min_cos ||
            std::abs(normal.dot((point - b.centre).normalized())) < min_cos)
          continue;
        const Eigen::Vector3d point_in_b = cb.rotation * point + cb.translation;
        if (!(point_in_b.z() > 0.0)) continue;
        const Eigen::Vector2d pixel = ProjectIdeal(cb, point_in_b);
        if (!(pixel.x() >= 0.0 && pixel.y() >= 0.0 && pixel.x() < cb.width - 1.0 && pixel.y() < cb.height - 1.0)) continue;
        const std::size_t nearest = static_cast<std::size_t>(std::lround(pixel.y())) * cb.width + std::lround(pixel.x());
        const float inverse_b = b.inverse_depth[nearest];
        if (!(inverse_b > 0.0f) || std::abs(1.0 / inverse_b - point_in_b.z()) > options.visibility_tolerance_m) continue;
        warped.at<uchar>(y, x) = cv::saturate_cast<uchar>(Bilinear(b.grey, pixel.x(), pixel.y()));
        samples.push_back({x, y, face, point, static_cast<float>(pixel.x()), static_cast<float>(pixel.y())});
      }
    cv::Mat flow;
    // The fast preset's patches and fewer descent steps at the same finest scale: 10-17% less
    // photo-refinement time than the medium preset, held-out PSNR within 0.02 dB (issue 23).
    cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST);
    dis->setFinestScale(finest_scale);
    if (finest_scale == 0) dis->setPatchStride(options.full_resolution_patch_stride);
    dis->setVariationalRefinementIterations(variational_iterations);
    dis->calc(warped, real, flow);
    // Where b's colour landed in a: the surface point both saw lies on a's ray through that pixel
    // and on b's ray through the pixel it was read from.
    for (const Sample& sample : samples) {
      const cv::Vec2f f = flow.at<cv::Vec2f>(sample.y, sample.x);
      const double magnitude = std::hypot(f[0], f[1]);
      if (!(magnitude <= options.max_flow_px)) continue;
      const Eigen::Vector3d ray_a = ca.rotation.transpose() *
                                    (a.K_inverse * Eigen::Vector3d(sample.x + crop.x + f[0], sample.y + crop.y + f[1], 1.0));
      const Eigen::Vector3d ray_b = cb.rotation.transpose() * (b.K_inverse * Eigen::Vector3d(sample.b_x, sample.b_y, 1.0));
      Eigen::Vector3d on_a, on_b;
      if (!ClosestPoints(a.centre, ray_a, b.centre, ray_b, &on_a, &on_b) || (on_a - on_b).norm() > options.max_ray_gap_m)
        continue;
      const double offset = (0.5 * (on_a + on_b) - sample.point).dot(face_normals.row(sample.face).transpose());
      if (!(std::abs(offset) <= options.max_offset_m)) continue;
      for (int k = 0; k < 3; ++k) {
        sums->offset(faces(sample.face, k)) += offset;
        sums->weight(faces(sample.face, k)) += 1.0;
      }
      sums->flow_sum += magnitude;
      ++sums->samples;
    }
  }
};

PhotoRefiner::PhotoRefiner(const Mesh& scan, const PhotoRefinementOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  impl_->faces = scan.faces;
  if (scan.num_faces() == 0) throw InputError("scan", "photo refinement: the scan has no faces");
  impl_->spread = std::make_unique<NormalisedDiffusion>(scan, options.spread_stiffness, "scan");
  impl_->spread->set_threads(options.threads);
  const bool full_resolution = options.full_resolution_rounds > 0 || options.flow_finest_scale == 0;
  if (full_resolution && options.full_resolution_spread_stiffness != options.spread_stiffness) {
    impl_->fine_spread = std::make_unique<NormalisedDiffusion>(scan, options.full_resolution_spread_stiffness, "scan");
    impl_->fine_spread->set_threads(options.threads);
  }
  impl_->rasterizer = std::make_unique<CpuRasterizer>(scan.faces, scan.num_vertices());
}

PhotoRefiner::~PhotoRefiner() = default;
PhotoRefiner::PhotoRefiner(PhotoRefiner&&) noexcept = default;
PhotoRefiner& PhotoRefiner::operator=(PhotoRefiner&&) noexcept = default;

RowMatrixX3d PhotoRefiner::Refine(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                                  const std::vector<Image>& images, PhotoRefinementSummary* summary_out,
                                  int rounds) const {
  const Impl& s = *impl_;
  const int n = static_cast<int>(vertices.rows());
  if (n != s.spread->num_vertices()) throw std::invalid_argument("PhotoRefiner: the vertex count differs from the scan's");
  if (cameras.size() != images.size()) throw std::invalid_argument("PhotoRefiner: one image per camera is needed");
  if (!vertices.allFinite()) throw std::invalid_argument("PhotoRefiner: non-finite vertices");
  const int num_views = static_cast<int>(cameras.size());
  std::vector<View> views(num_views);
  for (int c = 0; c < num_views; ++c) {
    const Camera& camera = cameras[c];
    const Image& image = images[c];
    if (image.width != camera.width || image.height != camera.height || image.type != PixelType::kUInt8 ||
        (image.channels != 1 && image.channels != 3))
      throw std::invalid_argument("PhotoRefiner: image " + std::to_string(c) + " is not an 8-bit frame of camera " +
                                  camera.name + "'s size");
  }
  ParallelFor(num_views, s.options.threads, [&](int c) {
    const Camera& camera = cameras[c];
    const Image& image = images[c];
    const Image ideal = camera.has_distortion() ? UndistortImage(camera, image) : image;
    const cv::Mat wrapped(ideal.height, ideal.width, ideal.channels == 3 ? CV_8UC3 : CV_8UC1,
                          const_cast<std::uint8_t*>(ideal.data.data()));
    if (ideal.channels == 3) cv::cvtColor(wrapped, views[c].grey, cv::COLOR_RGB2GRAY);
    else views[c].grey = wrapped.clone();
    views[c].camera = &camera;
    views[c].K_inverse = camera.K.inverse();
    views[c].centre = camera.center_in_world();
    views[c].inverse_depth.assign(static_cast<std::size_t>(camera.width) * camera.height, 0.0f);
    views[c].face_ids.assign(views[c].inverse_depth.size(), -1);
  });
  PhotoRefinementSummary summary;
  RowMatrixX3d current = vertices;
  if (num_views < 2) {
    if (summary_out) *summary_out = summary;
    return current;
  }
  // Each camera's neighbours: the cameras nearest in direction, seen from the scan's centre. A
  // pair of mutual neighbours is measured once per round, from alternating sides: the flow
  // between the two, computed in both directions, tells the same offsets twice (issue 23: half
  // the flow, -0.03 dB held-out PSNR on the studio default; one fixed side lost 0.08 dB).
  const Eigen::Vector3d centre = vertices.colwise().mean().transpose();
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < num_views; ++a) {
    std::vector<std::pair<double, int>> by_angle;
    const Eigen::Vector3d direction = (views[a].centre - centre).normalized();
    for (int b = 0; b < num_views; ++b)
      if (b != a) by_angle.push_back({-direction.dot((views[b].centre - centre).normalized()), b});
    std::sort(by_angle.begin(), by_angle.end());
    for (int k = 0; k < std::min<int>(s.options.neighbours, by_angle.size()); ++k) {
      const int b = by_angle[k].second;
      if (std::find(pairs.begin(), pairs.end(), std::make_pair(b, a)) == pairs.end()) pairs.push_back({a, b});
    }
  }
  const int threads = std::max(1, std::min<int>(s.options.threads, pairs.size()));
  // Calls work(0) .. work(threads - 1) concurrently.
  auto in_parallel = [threads](const std::function<void(int)>& work) { ParallelFor(threads, threads, work); };
  Mesh mesh;
  mesh.faces = s.faces;
  const int num_rounds = rounds >= 0 ? rounds : s.options.rounds;
  for (int round = 0; round < num_rounds; ++round) {
    mesh.vertices = current;
    const RowMatrixX3f as_float = current.cast<float>();
    std::vector<CpuRasterFrame> frames(threads);
    auto draw = [&](int part) {
      for (int c = part; c < num_views; c += threads) {
        View& view = views[c];
        FillBox(view.inverse_depth.data(), view.camera->width, view.box, 0.0f);  // what the last round drew
        s.rasterizer->Project(*view.camera, as_float, &frames[part]);
        view.box = s.rasterizer->Draw(frames[part], 0, view.camera->height, view.inverse_depth.data(), view.face_ids.data());
      }
    };
    const RowMatrixX3d face_normals = FaceNormals(mesh);
    const int finest_scale = round >= num_rounds - s.options.full_resolution_rounds ? 0 : s.options.flow_finest_scale;
    const int last_iterations =
        finest_scale == 0 ? s.options.full_resolution_variational_iterations : s.options.flow_variational_iterations;
    std::vector<OffsetSums> sums(threads, OffsetSums(n));
    auto measure = [&](int part) {
      for (std::size_t i = part; i < pairs.size(); i += threads) {
        const auto [a, b] = round % 2 == 0 ? pairs[i] : std::make_pair(pairs[i].second, pairs[i].first);
        s.MeasurePair(views[a], views[b], face_normals, finest_scale, round == num_rounds - 1 ? last_iterations : 0,
                      &sums[part]);
      }
    };
    in_parallel(draw);
    in_parallel(measure);
    Eigen::MatrixXd offsets = Eigen::MatrixXd::Zero(n, 1);
    std::vector<bool> measured(n, false);
    double flow_sum = 0.0;
    long long samples = 0;
    for (int part = 1; part < threads; ++part) {
      sums[0].offset += sums[part].offset;
      sums[0].weight += sums[part].weight;
    }
    for (const OffsetSums& part : sums) flow_sum += part.flow_sum, samples += part.samples;
    summary.measured_vertices = 0;
    for (int v = 0; v < n; ++v)
      if (sums[0].weight(v) > 0.0) {
        offsets(v, 0) = sums[0].offset(v) / sums[0].weight(v);
        measured[v] = true;
        ++summary.measured_vertices;
      }
    const double mean_flow = samples ? flow_sum / samples : 0.0;
    if (round == 0) summary.first_flow_px = mean_flow;
    summary.last_flow_px = mean_flow;
    summary.samples += samples;
    summary.rounds = round + 1;
    if (samples == 0) break;
    const NormalisedDiffusion& diffusion = finest_scale == 0 && s.fine_spread ? *s.fine_spread : *s.spread;
    const Eigen::MatrixXd spread = diffusion.Spread(offsets, measured, s.options.fade_weight);
    const RowMatrixX3d normals = VertexNormals(mesh);
    for (int v = 0; v < n; ++v) current.row(v) += s.options.step_gain * spread(v, 0) * normals.row(v);
  }
  if (!current.allFinite()) current = vertices;
  summary.mean_shift_m = n ? (current - vertices).rowwise().norm().mean() : 0.0;
  if (summary_out) *summary_out = summary;
  return current;
}

}  // namespace confluent
