#include "calib/synthetic_board.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"

namespace confluent {

void SyntheticBoardOptions::Check() const {
  const std::string owner = "SyntheticBoardOptions.";
  RequireOption(supersampling >= 1, owner + "supersampling", supersampling, ">= 1");
  RequireOption(noise_sigma >= 0.0, owner + "noise_sigma", noise_sigma, ">= 0");
  RequireOption(border_squares >= 0.0, owner + "border_squares", border_squares, ">= 0");
}

namespace {

constexpr int kInvalid = -3;     // ray misses the board plane (parallel or behind the camera)
constexpr int kOutside = -1;     // beyond the board
constexpr int kBorder = -2;      // white margin around the pattern

// Board plane seen from one camera for one pose.
struct PlaneView {
  Eigen::Matrix3d board_rotation;     // cam_from_board rotation
  Eigen::Vector3d board_translation;  // cam_from_board translation
  Eigen::Vector3d normal;             // board z in camera coordinates
  double offset = 0.0;                // normal . board_translation
  bool front = true;                  // camera sees the front (pattern) face

  // Board-plane coordinates (x, y) of the ray through undistorted normalized coords `n`.
  bool Intersect(const Eigen::Vector2d& n, Eigen::Vector2d* board_xy) const {
    const Eigen::Vector3d ray(n.x(), n.y(), 1.0);
    const double denominator = normal.dot(ray);
    if (std::abs(denominator) < 1e-12) return false;
    const double depth = offset / denominator;
    if (depth <= 0.0) return false;
    const Eigen::Vector3d relative = depth * ray - board_translation;
    *board_xy = Eigen::Vector2d(board_rotation.col(0).dot(relative), board_rotation.col(1).dot(relative));
    return true;
  }
};

struct BoardLayout {
  double square = 0.0;
  int cols = 0, rows = 0;
  double pattern_min_x = 0, pattern_max_x = 0, pattern_min_y = 0, pattern_max_y = 0;
  double board_min_x = 0, board_max_x = 0, board_min_y = 0, board_max_y = 0;

  BoardLayout(const CheckerboardSpec& board, double border_squares)
      : square(board.square_m), cols(board.cols), rows(board.rows) {
    pattern_min_x = -square;
    pattern_max_x = cols * square;
    pattern_min_y = -square;
    pattern_max_y = rows * square;
    const double border = border_squares * square;
    board_min_x = pattern_min_x - border;
    board_max_x = pattern_max_x + border;
    board_min_y = pattern_min_y - border;
    board_max_y = pattern_max_y + border;
  }

  // Region id: a square index >= 0, or kBorder / kOutside.
  int Region(const Eigen::Vector2d& p) const {
    if (p.x() < board_min_x || p.x() >= board_max_x || p.y() < board_min_y || p.y() >= board_max_y) return kOutside;
    if (p.x() < pattern_min_x || p.x() >= pattern_max_x || p.y() < pattern_min_y || p.y() >= pattern_max_y) return kBorder;
    const int i = static_cast<int>(std::floor(p.x() / square)) + 1;
    const int j = static_cast<int>(std::floor(p.y() / square)) + 1;
    return i * (rows + 2) + j;
  }
  bool RegionDark(int region) const {
    const int i = region / (rows + 2), j = region % (rows + 2);
    return (i + j) % 2 == 0;
  }
};

}  // namespace

CheckerboardRenderer::CheckerboardRenderer(const Camera& camera, const CheckerboardSpec& board,
                                           const SyntheticBoardOptions& options)
    : camera_(camera), board_(board), options_(options) {
  board_.Check();
  options_.Check();
  const int w = camera_.width, h = camera_.height;
  if (w <= 0 || h <= 0) throw UsageError("CheckerboardRenderer: camera " + camera_.name + " has no image size");
  const Eigen::Matrix3d k_inverse = camera_.K.inverse();
  lattice_.resize(static_cast<std::size_t>(w + 1) * (h + 1));
  for (int y = 0; y <= h; ++y)
    for (int x = 0; x <= w; ++x) {
      const Eigen::Vector3d n = k_inverse * Eigen::Vector3d(x - 0.5, y - 0.5, 1.0);
      lattice_[static_cast<std::size_t>(y) * (w + 1) + x] = camera_.Undistort(n.head<2>() / n.z());
    }
}

Image CheckerboardRenderer::Render(const Eigen::Isometry3d& world_from_board, std::uint32_t seed) const {
  const int w = camera_.width, h = camera_.height;
  const Eigen::Isometry3d cam_from_board = camera_.cam_from_world() * world_from_board;
  PlaneView plane;
  plane.board_rotation = cam_from_board.linear();
  plane.board_translation = cam_from_board.translation();
  plane.normal = plane.board_rotation.col(2);
  plane.offset = plane.normal.dot(plane.board_translation);
  // The camera centre in board coordinates has z < 0 when it faces the pattern.
  plane.front = (-(plane.board_rotation.transpose() * plane.board_translation)).z() < 0.0;
  const BoardLayout layout(board_, options_.border_squares);

  auto shade = [&](int region) {
    if (region == kInvalid || region == kOutside) return options_.background;
    if (!plane.front) return options_.back_side;
    if (region == kBorder) return options_.light;
    return layout.RegionDark(region) ? options_.dark : options_.light;
  };
  auto region_of = [&](const Eigen::Vector2d& n, Eigen::Vector2d* xy) {
    return plane.Intersect(n, xy) ? layout.Region(*xy) : kInvalid;
  };

  // Regions and board coordinates of the pixel-corner lattice.
  std::vector<int> regions(lattice_.size());
  std::vector<Eigen::Vector2d> board_xy(lattice_.size(), Eigen::Vector2d::Zero());
  for (std::size_t i = 0; i < lattice_.size(); ++i) regions[i] = region_of(lattice_[i], &board_xy[i]);

  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, options_.noise_sigma);
  Image image(w, h, 1, PixelType::kUInt8);
  const int n = options_.supersampling;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i00 = static_cast<std::size_t>(y) * (w + 1) + x, i10 = i00 + 1, i01 = i00 + w + 1, i11 = i01 + 1;
      const int r = regions[i00];
      bool uniform = r == regions[i10] && r == regions[i01] && r == regions[i11];
      if (uniform && (r == kBorder || r == kOutside)) {
        // Non-convex regions: uniform only if the pixel's footprint cannot reach the pattern / board.
        const double min_x = std::min({board_xy[i00].x(), board_xy[i10].x(), board_xy[i01].x(), board_xy[i11].x()});
        const double max_x = std::max({board_xy[i00].x(), board_xy[i10].x(), board_xy[i01].x(), board_xy[i11].x()});
        const double min_y = std::min({board_xy[i00].y(), board_xy[i10].y(), board_xy[i01].y(), board_xy[i11].y()});
        const double max_y = std::max({board_xy[i00].y(), board_xy[i10].y(), board_xy[i01].y(), board_xy[i11].y()});
        const bool touches_pattern = max_x >= layout.pattern_min_x && min_x < layout.pattern_max_x &&
                                     max_y >= layout.pattern_min_y && min_y < layout.pattern_max_y;
        const bool touches_board = max_x >= layout.board_min_x && min_x < layout.board_max_x &&
                                   max_y >= layout.board_min_y && min_y < layout.board_max_y;
        uniform = r == kBorder ? !touches_pattern && min_x >= layout.board_min_x && max_x < layout.board_max_x &&
                                     min_y >= layout.board_min_y && max_y < layout.board_max_y
                               : !touches_board;
      }
      double value = 0.0;
      if (uniform) {
        value = shade(r);
      } else {
        // Supersample: bilinear interpolation of the undistorted rays, exact plane intersection.
        const Eigen::Vector2d& a = lattice_[i00];
        const Eigen::Vector2d& b = lattice_[i10];
        const Eigen::Vector2d& c = lattice_[i01];
        const Eigen::Vector2d& d = lattice_[i11];
        double sum = 0.0;
        for (int sy = 0; sy < n; ++sy)
          for (int sx = 0; sx < n; ++sx) {
            const double u = (sx + 0.5) / n, v = (sy + 0.5) / n;
            const Eigen::Vector2d ray = (1 - v) * ((1 - u) * a + u * b) + v * ((1 - u) * c + u * d);
            Eigen::Vector2d xy;
            sum += shade(region_of(ray, &xy));
          }
        value = sum / (n * n);
      }
      if (options_.noise_sigma > 0.0) value += noise(rng);
      image.at<std::uint8_t>(x, y) = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  return image;
}

Image RenderCheckerboard(const Camera& camera, const CheckerboardSpec& board, const Eigen::Isometry3d& world_from_board,
                         const SyntheticBoardOptions& options) {
  return CheckerboardRenderer(camera, board, options).Render(world_from_board, options.seed);
}

std::vector<Eigen::Vector2d> ProjectCheckerboard(const Camera& camera, const CheckerboardSpec& board,
                                                 const Eigen::Isometry3d& world_from_board) {
  std::vector<Eigen::Vector2d> pixels;
  for (const Eigen::Vector3d& corner : board.CornersInBoard()) pixels.push_back(camera.Project(world_from_board * corner));
  return pixels;
}

bool CheckerboardVisible(const Camera& camera, const CheckerboardSpec& board, const Eigen::Isometry3d& world_from_board,
                         double margin_px, double max_obliquity_deg) {
  const Eigen::Isometry3d board_from_world = world_from_board.inverse();
  const Eigen::Vector3d centre_in_board = board_from_world * camera.center_in_world();
  if (centre_in_board.z() >= 0.0) return false;
  const Eigen::Vector3d board_middle(0.5 * (board.cols - 1) * board.square_m, 0.5 * (board.rows - 1) * board.square_m, 0.0);
  const Eigen::Vector3d to_camera = (centre_in_board - board_middle).normalized();
  const double obliquity_deg = std::acos(std::clamp(-to_camera.z(), -1.0, 1.0)) * 180.0 / M_PI;
  if (obliquity_deg > max_obliquity_deg) return false;
  for (const Eigen::Vector3d& corner : board.CornersInBoard()) {
    Eigen::Vector2d pixel;
    if (!camera.ProjectChecked(world_from_board * corner, &pixel)) return false;
    if (pixel.x() < margin_px || pixel.y() < margin_px || pixel.x() > camera.width - 1 - margin_px ||
        pixel.y() > camera.height - 1 - margin_px)
      return false;
  }
  return true;
}

Rig MakeRingRig(int count, double radius_m, double height_m, const Eigen::Vector3d& target_in_world, int width,
                int height, double focal_px, const Vector5d& dist) {
  Rig rig;
  for (int i = 0; i < count; ++i) {
    const double angle = 2.0 * M_PI * i / count;
    const Eigen::Vector3d centre(radius_m * std::cos(angle), radius_m * std::sin(angle), height_m);
    char name[16];
    std::snprintf(name, sizeof(name), "cam%02d", i);
    Camera camera = LookAtCamera(name, centre, target_in_world, width, height, focal_px);
    camera.dist = dist;
    rig.cameras.push_back(camera);
  }
  return rig;
}

std::vector<Eigen::Isometry3d> MakeBoardPoses(int count, const CheckerboardSpec& board, double radius_m, double min_z_m,
                                              double max_z_m, double max_tilt_deg, double max_roll_deg,
                                              std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto symmetric = [&](double limit) { return (2.0 * unit(rng) - 1.0) * limit; };
  const double deg = M_PI / 180.0;
  const Eigen::Vector3d board_middle(0.5 * (board.cols - 1) * board.square_m, 0.5 * (board.rows - 1) * board.square_m, 0.0);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < count; ++i) {
    const double azimuth = 2.0 * M_PI * unit(rng);
    const Eigen::Vector3d facing(std::cos(azimuth), std::sin(azimuth), 0.0);
    Eigen::Matrix3d base;
    base.col(2) = -facing;
    base.col(1) = -Eigen::Vector3d::UnitZ();
    base.col(0) = base.col(1).cross(base.col(2));
    const Eigen::Matrix3d rotation = base * Eigen::AngleAxisd(symmetric(max_tilt_deg) * deg, Eigen::Vector3d::UnitX()) *
                                     Eigen::AngleAxisd(symmetric(max_tilt_deg) * deg, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(symmetric(max_roll_deg) * deg, Eigen::Vector3d::UnitZ());
    const double r = radius_m * std::sqrt(unit(rng)), phi = 2.0 * M_PI * unit(rng);
    const Eigen::Vector3d centre(r * std::cos(phi), r * std::sin(phi), min_z_m + (max_z_m - min_z_m) * unit(rng));
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation;
    pose.translation() = centre - rotation * board_middle;
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace confluent
