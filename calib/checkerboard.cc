#include "calib/checkerboard.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"

namespace confluent {

std::vector<Eigen::Vector3d> CheckerboardSpec::CornersInBoard() const {
  std::vector<Eigen::Vector3d> corners;
  corners.reserve(static_cast<std::size_t>(num_corners()));
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) corners.emplace_back(col * square_m, row * square_m, 0.0);
  return corners;
}

void CheckerboardSpec::Check() const {
  RequireOption(cols >= 2, "CheckerboardSpec.cols", cols, ">= 2 (inner corners)");
  RequireOption(rows >= 2, "CheckerboardSpec.rows", rows, ">= 2 (inner corners)");
  RequireOption(square_m > 0.0 && std::isfinite(square_m), "CheckerboardSpec.square_m", square_m,
                "> 0 and finite (metres)");
}

void ParseBoardSize(const std::string& text, int* cols, int* rows) {
  const std::size_t x = text.find_first_of("xX");
  auto bad = [&]() { return UsageError("--board: expected COLSxROWS inner corners like 8x6, got '" + text + "'"); };
  if (x == std::string::npos || x == 0 || x + 1 >= text.size()) throw bad();
  const std::string a = text.substr(0, x), b = text.substr(x + 1);
  for (const std::string& part : {a, b})
    if (part.find_first_not_of("0123456789") != std::string::npos) throw bad();
  *cols = std::stoi(a);
  *rows = std::stoi(b);
  if (*cols < 2 || *rows < 2) throw bad();
}

void CheckerboardDetectOptions::Check() const {
  const std::string owner = "CheckerboardDetectOptions.";
  RequireOption(subpix_half_window_px >= 0, owner + "subpix_half_window_px", subpix_half_window_px, ">= 0");
  RequireOption(max_detection_width_px >= 0, owner + "max_detection_width_px", max_detection_width_px, ">= 0");
  RequireOption(min_corner_spacing_px >= 0.0, owner + "min_corner_spacing_px", min_corner_spacing_px, ">= 0");
  RequireOption(max_unfitted_corners >= 0, owner + "max_unfitted_corners", max_unfitted_corners, ">= 0");
}

void HalfTurnCorners(std::vector<Eigen::Vector2d>* corners_px) {
  std::reverse(corners_px->begin(), corners_px->end());
}

namespace {

// 8-bit single-channel copy of `image` (RGB(A) averaged with luma weights).
cv::Mat ToGray8(const Image& image) {
  if (image.empty()) return {};
  const int depth = image.type == PixelType::kUInt8 ? CV_8U : image.type == PixelType::kUInt16 ? CV_16U : CV_32F;
  const cv::Mat view(image.height, image.width, CV_MAKETYPE(depth, image.channels),
                     const_cast<std::uint8_t*>(image.data.data()));
  cv::Mat gray;
  if (image.channels == 1) {
    gray = view;
  } else if (image.channels == 3) {
    cv::cvtColor(view, gray, cv::COLOR_RGB2GRAY);
  } else if (image.channels == 4) {
    cv::cvtColor(view, gray, cv::COLOR_RGBA2GRAY);
  } else {
    cv::extractChannel(view, gray, 0);
  }
  cv::Mat gray8;
  const double scale = depth == CV_8U ? 1.0 : depth == CV_16U ? 1.0 / 257.0 : 255.0;
  gray.convertTo(gray8, CV_8U, scale);
  return gray8;
}

double SampleBilinear(const cv::Mat& gray, double x, double y) {
  x = std::clamp(x, 0.0, gray.cols - 1.001);
  y = std::clamp(y, 0.0, gray.rows - 1.001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int xx, int yy) { return static_cast<double>(gray.at<std::uint8_t>(yy, xx)); };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// Mean intensity of the board square diagonally outside grid corner (row, col), on the side
// given by the steps to the neighbouring corners.
double OuterSquareIntensity(const cv::Mat& gray, const Eigen::Vector2d& corner, const Eigen::Vector2d& step_col,
                            const Eigen::Vector2d& step_row) {
  double sum = 0.0;
  int count = 0;
  for (double a : {0.35, 0.5, 0.65})
    for (double b : {0.35, 0.5, 0.65}) {
      const Eigen::Vector2d p = corner + a * step_col + b * step_row;
      sum += SampleBilinear(gray, p.x(), p.y());
      ++count;
    }
  return sum / count;
}

// Puts a full detection into the canonical order documented in checkerboard.h.
void Canonicalize(const cv::Mat& gray, const CheckerboardSpec& board, std::vector<Eigen::Vector2d>* corners) {
  const int cols = board.cols, rows = board.rows;
  auto at = [&](int row, int col) -> Eigen::Vector2d& { return (*corners)[static_cast<std::size_t>(row * cols + col)]; };
  // Handedness: board x (along a row) cross board y (down a column) must be positive in the
  // y-down image, i.e. the board is seen from its front.
  const Eigen::Vector2d along_row = at(0, cols - 1) - at(0, 0);
  const Eigen::Vector2d along_col = at(rows - 1, 0) - at(0, 0);
  if (along_row.x() * along_col.y() - along_row.y() * along_col.x() < 0.0)
    for (int row = 0; row < rows; ++row)
      std::reverse(corners->begin() + row * cols, corners->begin() + (row + 1) * cols);
  bool half_turn = false;
  if (board.half_turn_symmetric()) {
    const Eigen::Vector2d& first = corners->front();
    const Eigen::Vector2d& last = corners->back();
    half_turn = first.x() + first.y() > last.x() + last.y();
  } else {
    // The outer square at corner 0 must be the dark one.
    const double first = OuterSquareIntensity(gray, at(0, 0), at(0, 0) - at(0, 1), at(0, 0) - at(1, 0));
    const double last = OuterSquareIntensity(gray, at(rows - 1, cols - 1), at(rows - 1, cols - 1) - at(rows - 1, cols - 2),
                                             at(rows - 1, cols - 1) - at(rows - 2, cols - 1));
    half_turn = first > last;
  }
  if (half_turn) HalfTurnCorners(corners);
}

// Scales pixel positions by (sx, sy) between an image and a resized copy of it (pixel centres
// at integers in both).
void ScalePixelCentres(double sx, double sy, std::vector<cv::Point2f>* points) {
  for (auto& p : *points) {
    p.x = static_cast<float>((p.x + 0.5) * sx - 0.5);
    p.y = static_cast<float>((p.y + 0.5) * sy - 0.5);
  }
}

double MinSpacing(const std::vector<cv::Point2f>& points, int cols, int rows) {
  double best = 1e30;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const cv::Point2f& p = points[static_cast<std::size_t>(row * cols + col)];
      if (col + 1 < cols) best = std::min(best, static_cast<double>(cv::norm(points[row * cols + col + 1] - p)));
      if (row + 1 < rows) best = std::min(best, static_cast<double>(cv::norm(points[(row + 1) * cols + col] - p)));
    }
  return best;
}

// Fits an ideal blurred X-junction to the pixels of `gray` within `radius` of `start`:
//   I(p) = m + a tanh(u1 / s) tanh(u2 / s),  u_k = (p - c) . (cos t_k, sin t_k),
// i.e. two straight edges through the corner c with normal angles t1, t2, grey levels m +- a
// and edge blur s (pixel centres at integer coordinates). The edges stay straight under
// perspective, and the model is point-symmetric about c, so a mismatch of the blur profile
// (pixel box filter, optics) does not move c. Levenberg-Marquardt with an analytic Jacobian.
// Returns false (corner unchanged) when the window holds too few pixels or the fit is implausible.
bool FitXJunction(const cv::Mat& gray, const Eigen::Vector2d& start, const Eigen::Vector2d& normal1,
                  const Eigen::Vector2d& normal2, double radius, Eigen::Vector2d* corner) {
  const int x0 = std::max(0, static_cast<int>(std::floor(start.x() - radius)));
  const int x1 = std::min(gray.cols - 1, static_cast<int>(std::ceil(start.x() + radius)));
  const int y0 = std::max(0, static_cast<int>(std::floor(start.y() - radius)));
  const int y1 = std::min(gray.rows - 1, static_cast<int>(std::ceil(start.y() + radius)));
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> values;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p(x, y);
      if ((p - start).squaredNorm() > radius * radius) continue;
      pixels.push_back(p);
      values.push_back(gray.at<std::uint8_t>(y, x));
    }
  const int n = static_cast<int>(pixels.size());
  if (n < 12) return false;
  // Parameters: cx, cy, t1, t2, m, a, s.
  Eigen::Matrix<double, 7, 1> x;
  x << start.x(), start.y(), std::atan2(normal1.y(), normal1.x()), std::atan2(normal2.y(), normal2.x()), 0.0, 0.0, 0.7;
  {  // m and a by linear least squares for the starting geometry.
    Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d d = pixels[i] - start;
      const Eigen::Vector2d row(1.0, std::tanh(d.dot(normal1) / x[6]) * std::tanh(d.dot(normal2) / x[6]));
      normal += row * row.transpose();
      rhs += row * values[i];
    }
    const Eigen::Vector2d ma = normal.ldlt().solve(rhs);
    x[4] = ma[0];
    x[5] = ma[1];
  }
  auto evaluate = [&](const Eigen::Matrix<double, 7, 1>& params, Eigen::Matrix<double, 7, 7>* jtj,
                      Eigen::Matrix<double, 7, 1>* jtr) {
    const Eigen::Vector2d c(params[0], params[1]);
    const Eigen::Vector2d n1(std::cos(params[2]), std::sin(params[2])), n2(std::cos(params[3]), std::sin(params[3]));
    const Eigen::Vector2d t1(-n1.y(), n1.x()), t2(-n2.y(), n2.x());
    const double m = params[4], a = params[5], blur = params[6];
    double cost = 0.0;
    if (jtj) jtj->setZero();
    if (jtr) jtr->setZero();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d d = pixels[i] - c;
      const double u1 = d.dot(n1), u2 = d.dot(n2);
      const double s1 = std::tanh(u1 / blur), s2 = std::tanh(u2 / blur);
      const double r = m + a * s1 * s2 - values[i];
      cost += r * r;
      if (!jtj) continue;
      const double ds1 = (1.0 - s1 * s1) / blur, ds2 = (1.0 - s2 * s2) / blur;  // d s / d u
      Eigen::Matrix<double, 7, 1> j;
      const Eigen::Vector2d dc = -a * (s2 * ds1 * n1 + s1 * ds2 * n2);
      j << dc.x(), dc.y(), a * s2 * ds1 * d.dot(t1), a * s1 * ds2 * d.dot(t2), 1.0, s1 * s2,
          -a * (s2 * ds1 * u1 + s1 * ds2 * u2) / blur;
      *jtj += j * j.transpose();
      *jtr += j * r;
    }
    return cost;
  };
  Eigen::Matrix<double, 7, 7> jtj;
  Eigen::Matrix<double, 7, 1> jtr;
  double cost = evaluate(x, &jtj, &jtr);
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 50; ++iteration) {
    Eigen::Matrix<double, 7, 7> damped = jtj;
    damped.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-9);
    const Eigen::Matrix<double, 7, 1> step = damped.ldlt().solve(-jtr);
    if (!step.allFinite()) return false;
    Eigen::Matrix<double, 7, 1> trial = x + step;
    if (trial[6] <= 0.2) trial[6] = 0.2;
    const double trial_cost = evaluate(trial, nullptr, nullptr);
    if (trial_cost < cost) {
      x = trial;
      cost = evaluate(x, &jtj, &jtr);
      lambda = std::max(lambda / 4.0, 1e-9);
      if (step.head<2>().norm() < 1e-5) break;
    } else {
      lambda *= 8.0;
      if (lambda > 1e8) break;
    }
  }
  const Eigen::Vector2d fitted(x[0], x[1]);
  // Plausibility: little motion from the start, some contrast, a blur that is not absurd.
  if (!x.allFinite() || (fitted - start).norm() > radius || std::abs(x[5]) < 5.0 || x[6] > 0.5 * radius)
    return false;
  *corner = fitted;
  return true;
}

// Refines every corner of a full detection (grid order: row-major, `cols` per row) with
// FitXJunction, re-centring the window on the fit until it stays put. The window radius keeps
// the fit clear of the neighbouring squares' edges. A second round retries the corners whose
// fit failed, with edge directions and clearances from the refined neighbours, and also from
// the midpoints of their grid neighbours (the initial detection is sometimes a few pixels off
// on steep boards). Returns the number of corners that could not be fitted (those keep their
// input position).
int RefineCornersByModelFit(const cv::Mat& gray, int cols, int rows, std::vector<cv::Point2f>* points) {
  std::vector<Eigen::Vector2d> current;
  for (const cv::Point2f& p : *points) current.emplace_back(p.x, p.y);
  std::vector<bool> fitted_ok(current.size(), false);
  for (int round = 0; round < 2; ++round) {
    const std::vector<Eigen::Vector2d> input = current;
    auto at = [&](int row, int col) { return input[static_cast<std::size_t>(row * cols + col)]; };
    for (int row = 0; row < rows; ++row)
      for (int col = 0; col < cols; ++col) {
        const std::size_t index = static_cast<std::size_t>(row * cols + col);
        if (round == 1 && fitted_ok[index]) continue;
        const Eigen::Vector2d p = at(row, col);
        // Edge directions through the corner, from its grid neighbours.
        const Eigen::Vector2d along_row = (at(row, std::min(col + 1, cols - 1)) - at(row, std::max(col - 1, 0))).normalized();
        const Eigen::Vector2d along_col = (at(std::min(row + 1, rows - 1), col) - at(std::max(row - 1, 0), col)).normalized();
        auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return std::abs(a.x() * b.y() - a.y() * b.x()); };
        // Distance to the nearest parallel edge: the lines through the neighbouring corners.
        double clearance = 1e30;
        for (int dc : {-1, 1})
          if (col + dc >= 0 && col + dc < cols) clearance = std::min(clearance, cross(along_col, at(row, col + dc) - p));
        for (int dr : {-1, 1})
          if (row + dr >= 0 && row + dr < rows) clearance = std::min(clearance, cross(along_row, at(row + dr, col) - p));
        const double radius = std::clamp(clearance - 1.5, 2.0, 8.0);
        const Eigen::Vector2d normal_row(-along_row.y(), along_row.x()), normal_col(-along_col.y(), along_col.x());
        std::vector<Eigen::Vector2d> starts = {p};
        if (round == 1) {
          Eigen::Vector2d sum = Eigen::Vector2d::Zero();
          int count = 0;
          if (col > 0 && col + 1 < cols) {
            sum += 0.5 * (at(row, col - 1) + at(row, col + 1));
            ++count;
          }
          if (row > 0 && row + 1 < rows) {
            sum += 0.5 * (at(row - 1, col) + at(row + 1, col));
            ++count;
          }
          if (count > 0) starts.push_back(sum / count);
        }
        for (const Eigen::Vector2d& start : starts) {
          Eigen::Vector2d centre = start;
          for (int pass = 0; pass < 4 && !fitted_ok[index]; ++pass) {
            Eigen::Vector2d fitted;
            if (!FitXJunction(gray, centre, normal_row, normal_col, radius, &fitted)) break;
            const double moved = (fitted - centre).norm();
            centre = fitted;
            if (moved < 0.25) {
              current[index] = fitted;
              fitted_ok[index] = true;
            }
          }
          if (fitted_ok[index]) break;
        }
      }
  }
  int failures = 0;
  for (std::size_t i = 0; i < current.size(); ++i) {
    if (!fitted_ok[i]) {
      ++failures;
      continue;
    }
    (*points)[i] = cv::Point2f(static_cast<float>(current[i].x()), static_cast<float>(current[i].y()));
  }
  return failures;
}

}  // namespace

bool DetectCheckerboard(const Image& image, const CheckerboardSpec& board, const CheckerboardDetectOptions& options,
                        std::vector<Eigen::Vector2d>* corners_px) {
  board.Check();
  options.Check();
  corners_px->clear();
  const cv::Mat gray = ToGray8(image);
  if (gray.empty()) return false;
  const cv::Size pattern(board.cols, board.rows);

  // Optionally detect on a downscaled copy of a large image.
  double scale = 1.0;
  cv::Mat work = gray;
  if (options.max_detection_width_px > 0 && gray.cols > options.max_detection_width_px) {
    scale = static_cast<double>(options.max_detection_width_px) / gray.cols;
    cv::resize(gray, work, cv::Size(), scale, scale, cv::INTER_AREA);
  }
  std::vector<cv::Point2f> points;
  bool found = false;
  bool refined = false;
  if (options.try_classic)
    found = cv::findChessboardCorners(work, pattern, points,
                                      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
  if (!found && options.try_sector_based) {
    found = cv::findChessboardCornersSB(work, pattern, points, cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY);
    refined = found;
  }
  // Scale factors (horizontal, vertical) from `gray` to the image the corners are refined on:
  // a board found only in a stretched copy keeps the sector detector's accuracy refinement made
  // there, and the model fit runs on the same stretch of the full-resolution image. At 1x the
  // 3-4 px between rows of a grazing board put neighbouring corners inside the cornerSubPix
  // window and it drifts (utrecht_4cam cam4: 0.58 px RMS from a homography, against 0.18 px).
  double refine_scale[2] = {1.0, 1.0};
  if (!found && options.try_vertical_stretch) {
    // The last copy also magnifies a small board (try_magnified_stretch): the sector detector
    // needs a few pixels per square horizontally too (utrecht_4cam cam4).
    const double kStretches[][2] = {{1.0, 2.0}, {1.0, 3.0}, {1.0, 4.0}, {1.5, 4.5}};
    for (const auto& stretch : kStretches) {
      if (stretch[0] != 1.0 && !options.try_magnified_stretch) continue;
      cv::Mat stretched;
      cv::resize(work, stretched, cv::Size(), stretch[0], stretch[1], cv::INTER_CUBIC);
      found = cv::findChessboardCornersSB(stretched, pattern, points, cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY);
      if (!found) continue;
      // Back to the unstretched image (pixel centres at integers in both).
      ScalePixelCentres(1.0 / stretch[0], 1.0 / stretch[1], &points);
      refine_scale[0] = stretch[0];
      refine_scale[1] = stretch[1];
      refined = true;  // findChessboardCornersSB's accuracy refinement, in the stretched copy
      break;
    }
  }
  if (!found || static_cast<int>(points.size()) != board.num_corners()) return false;
  if (scale != 1.0) {
    for (auto& p : points) p *= static_cast<float>(1.0 / scale);
    refined = false;
  }
  if (MinSpacing(points, board.cols, board.rows) < options.min_corner_spacing_px) return false;

  cv::Mat refine_image = gray;
  const bool stretched = refine_scale[0] != 1.0 || refine_scale[1] != 1.0;
  if (stretched) {
    cv::resize(gray, refine_image, cv::Size(), refine_scale[0], refine_scale[1], cv::INTER_CUBIC);
    ScalePixelCentres(refine_scale[0], refine_scale[1], &points);
  }
  if (!refined || options.subpix_half_window_px > 0) {
    int half = options.subpix_half_window_px;
    if (half == 0) half = std::clamp(static_cast<int>(std::floor(0.5 * MinSpacing(points, board.cols, board.rows))), 2, 15);
    cv::cornerSubPix(refine_image, points, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  }
  if (options.model_refinement) {
    // A mild Gaussian blur gives every edge a smooth profile that the tanh model follows; on a
    // sharp, anti-aliased edge the one mixed pixel alone cannot pin the blur and the fit stalls.
    cv::Mat smooth;
    cv::GaussianBlur(refine_image, smooth, cv::Size(0, 0), 0.8);
    const std::vector<cv::Point2f> detected = points;
    if (RefineCornersByModelFit(smooth, board.cols, board.rows, &points) > options.max_unfitted_corners) {
      // In a strongly stretched copy the edge blur is anisotropic and the X-junction model may
      // not fit every corner (utrecht_4cam cam4); the sector detector's refinement is then kept.
      if (!stretched) return false;
      points = detected;
    }
  }
  if (stretched) ScalePixelCentres(1.0 / refine_scale[0], 1.0 / refine_scale[1], &points);
  corners_px->reserve(points.size());
  for (const auto& p : points) corners_px->emplace_back(p.x, p.y);
  Canonicalize(gray, board, corners_px);
  return true;
}

}  // namespace confluent
