#include "tests/silhouette/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/cv_interop.h"

namespace confluent::testing {

namespace {

std::uint8_t Clamp8(double value) { return static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L)); }

}  // namespace

Image MakeTexturedPlate(int width, int height, unsigned seed) {
  Image plate(width, height, 3);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double phase = 6.28 * uniform(rng);
  const int horizon = height * 2 / 5;
  const int tile = std::max(8, width / 10);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double rgb[3];
      if (y < horizon) {  // wall: warm grey with a vertical gradient and a faint stripe texture
        const double shade = 150 + 40.0 * y / horizon + 6 * std::sin(0.7 * x + phase);
        rgb[0] = shade + 10; rgb[1] = shade; rgb[2] = shade - 15;
      } else {  // floor: two-tone tiles with a grain texture, darker towards the back
        const bool odd = ((x / tile) + ((y - horizon) / (tile / 2))) % 2;
        const double grain = 8 * std::sin(0.9 * x + 0.4 * y + phase) * std::sin(0.5 * y);
        const double base = (odd ? 135 : 105) + grain + 20.0 * (y - horizon) / (height - horizon);
        rgb[0] = base + 12; rgb[1] = base + 4; rgb[2] = base - 10;
      }
      for (int c = 0; c < 3; ++c) plate.at<std::uint8_t>(x, y, c) = Clamp8(rgb[c]);
    }
  // Posters on the wall: saturated rectangles.
  cv::Mat view = AsCvMat(plate);
  for (int k = 0; k < 4; ++k) {
    const int w = width / 10 + static_cast<int>(uniform(rng) * width / 10);
    const int h = horizon / 3 + static_cast<int>(uniform(rng) * horizon / 3);
    const int x = static_cast<int>(uniform(rng) * (width - w));
    const int y = static_cast<int>(uniform(rng) * (horizon - h));
    cv::rectangle(view, cv::Rect(x, y, w, h),
                  cv::Scalar(60 + 180 * uniform(rng), 60 + 180 * uniform(rng), 60 + 180 * uniform(rng)), cv::FILLED);
  }
  return plate;
}

Image MakeGreenScreen(int width, int height, unsigned seed) {
  Image screen(width, height, 3);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      // Folds: brightness between 0.45 and 1.1, a little lighting tint.
      const double fold = 0.78 + 0.32 * std::sin(0.11 * x + 0.03 * y) * std::sin(0.05 * y + 1.0);
      screen.at<std::uint8_t>(x, y, 0) = Clamp8(fold * (40 + 10.0 * y / height));
      screen.at<std::uint8_t>(x, y, 1) = Clamp8(fold * 150);
      screen.at<std::uint8_t>(x, y, 2) = Clamp8(fold * 65);
    }
  cv::Mat view = AsCvMat(screen);
  for (int k = 0; k < 40; ++k)  // tracking markers
    cv::circle(view, cv::Point(static_cast<int>(uniform(rng) * width), static_cast<int>(uniform(rng) * height)), 1,
               cv::Scalar(235, 235, 235), cv::FILLED);
  return screen;
}

Image DrawActor(Image* image, const ActorPlacement& p, double spill) {
  const double s = p.height_px / 170.0;
  const cv::Point2d feet(p.feet_x, p.feet_y);
  auto at = [&](double dx, double dy) { return cv::Point(cvRound(feet.x + dx * s), cvRound(feet.y - dy * s)); };
  auto axes = [&](double ax, double ay) { return cv::Size(std::max(1, cvRound(ax * s)), std::max(1, cvRound(ay * s))); };
  cv::Mat mask = cv::Mat::zeros(image->height, image->width, CV_8U);
  cv::Mat colour(image->height, image->width, CV_8UC3, cv::Scalar(0, 0, 0));
  auto part = [&](cv::Point centre, cv::Size size, double angle, cv::Scalar rgb) {
    cv::ellipse(colour, centre, size, angle, 0, 360, rgb, cv::FILLED);
    cv::ellipse(mask, centre, size, angle, 0, 360, cv::Scalar(255), cv::FILLED);
  };
  const cv::Scalar trousers(40, 35, 70), shirt(190, 60, 50), skin(215, 165, 135), hair(30, 25, 20), shoes(20, 20, 20);
  part(at(-12, 40), axes(9, 42), 4, trousers);     // legs
  part(at(12, 40), axes(9, 42), -4, trousers);
  part(at(-12, 3), axes(11, 4), 0, shoes);
  part(at(12, 3), axes(11, 4), 0, shoes);
  part(at(0, 110), axes(24, 34), 0, shirt);        // torso
  part(at(-30, 108), axes(7, 30), 14, shirt);      // arms
  part(at(30, 108), axes(7, 30), -14, shirt);
  part(at(-38, 74), axes(6, 8), 0, skin);          // left hand, attached
  if (p.hand_detached) {
    part(at(50, 60), axes(6, 7), 0, skin);         // right hand, a few pixels from the arm
  } else {
    part(at(38, 74), axes(6, 8), 0, skin);
  }
  part(at(0, 153), axes(11, 13), 0, skin);         // head with hair
  part(at(0, 160), axes(11, 7), 0, hair);
  cv::Mat target = AsCvMat(*image);
  colour.copyTo(target, mask);
  if (spill > 0) {
    cv::Mat inner;
    cv::erode(mask, inner, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
    for (int y = 0; y < image->height; ++y)
      for (int x = 0; x < image->width; ++x)
        if (mask.at<std::uint8_t>(y, x) && !inner.at<std::uint8_t>(y, x))
          image->at<std::uint8_t>(x, y, 1) = Clamp8(image->at<std::uint8_t>(x, y, 1) * (1 + spill));
  }
  return ImageFromCvMat(mask);
}

void DarkenEllipse(Image* image, double cx, double cy, double ax, double ay, double darkest) {
  for (int y = 0; y < image->height; ++y)
    for (int x = 0; x < image->width; ++x) {
      const double r2 = (x - cx) * (x - cx) / (ax * ax) + (y - cy) * (y - cy) / (ay * ay);
      if (r2 >= 1) continue;
      const double factor = darkest + (1 - darkest) * r2 * r2;
      for (int c = 0; c < image->channels; ++c) {
        std::uint8_t& v = image->at<std::uint8_t>(x, y, c);
        v = Clamp8(v * factor);
      }
    }
}

void AddNoise(Image* image, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  for (std::uint8_t& v : image->data) v = Clamp8(v + normal(rng));
}

double Iou(const Image& a, const Image& b) {
  std::size_t both = 0, either = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    both += a.data[i] && b.data[i];
    either += a.data[i] || b.data[i];
  }
  return either ? static_cast<double>(both) / either : 1.0;
}

}  // namespace confluent::testing
