#include "calib/checkerboard.h"

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
  if (cols < 2 || rows < 2)
    throw UsageError("checkerboard: needs at least 2x2 inner corners, got " + std::to_string(cols) + "x" +
                     std::to_string(rows));
  if (!(square_m > 0.0) || !std::isfinite(square_m))
    throw UsageError("checkerboard: square size must be positive, got " + std::to_string(square_m) + " m");
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
  if (subpix_half_window_px < 0) throw UsageError("CheckerboardDetectOptions: subpix_half_window_px must be >= 0");
  if (max_detection_width_px < 0) throw UsageError("CheckerboardDetectOptions: max_detection_width_px must be >= 0");
  if (!(min_corner_spacing_px >= 0.0)) throw UsageError("CheckerboardDetectOptions: min_corner_spacing_px must be >= 0");
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
  if (!found || static_cast<int>(points.size()) != board.num_corners()) return false;
  if (scale != 1.0) {
    for (auto& p : points) p *= static_cast<float>(1.0 / scale);
    refined = false;
  }
  const double spacing = MinSpacing(points, board.cols, board.rows);
  if (spacing < options.min_corner_spacing_px) return false;
  if (!refined || options.subpix_half_window_px > 0) {
    int half = options.subpix_half_window_px;
    if (half == 0) half = std::clamp(static_cast<int>(std::floor(0.5 * spacing)), 2, 15);
    cv::cornerSubPix(gray, points, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  }
  corners_px->reserve(points.size());
  for (const auto& p : points) corners_px->emplace_back(p.x, p.y);
  Canonicalize(gray, board, corners_px);
  return true;
}

}  // namespace confluent
