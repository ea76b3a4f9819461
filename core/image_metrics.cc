#include "core/image_metrics.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "core/cv_interop.h"

namespace confluent {
namespace {

int ComparedChannels(const Image& image) { return image.channels >= 3 ? 3 : 1; }

void CheckPair(const Image& a, const Image& b, const Image& mask) {
  if (a.empty() || b.empty()) throw std::invalid_argument("image metrics: empty image");
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("image metrics: images differ in size (" + std::to_string(a.width) + "x" +
                                std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                                std::to_string(b.height) + ")");
  if (ComparedChannels(a) != ComparedChannels(b))
    throw std::invalid_argument("image metrics: images differ in channel count");
  if (!mask.empty() && (mask.width != a.width || mask.height != a.height))
    throw std::invalid_argument("image metrics: mask size differs from the images");
}

// The compared channels as CV_64F in [0, 1].
cv::Mat ToUnitDouble(const Image& image) {
  cv::Mat mat = AsCvMat(image);
  const int channels = ComparedChannels(image);
  if (image.channels != channels) {
    std::vector<cv::Mat> planes;
    cv::split(mat, planes);
    planes.resize(channels);
    cv::merge(planes, mat);
  }
  const double scale = image.type == PixelType::kUInt8 ? 1.0 / 255.0 : image.type == PixelType::kUInt16 ? 1.0 / 65535.0 : 1.0;
  cv::Mat out;
  mat.convertTo(out, CV_MAKETYPE(CV_64F, channels), scale);
  return out;
}

// 8-bit 0/1 mask of counted pixels.
cv::Mat CountedPixels(const Image& mask, int width, int height) {
  if (mask.empty()) return cv::Mat(height, width, CV_8U, cv::Scalar(1));
  cv::Mat m = AsCvMat(mask);
  if (mask.channels > 1) {
    std::vector<cv::Mat> planes;
    cv::split(m, planes);
    m = planes[0];
  }
  cv::Mat counted;
  cv::compare(m, 0, counted, cv::CMP_GT);
  if (cv::countNonZero(counted) == 0) throw std::invalid_argument("image metrics: the mask has no set pixel");
  return counted;
}

cv::Mat Luma(const cv::Mat& unit) {
  if (unit.channels() == 1) return unit;
  cv::Mat luma;
  cv::transform(unit, luma, cv::Matx13d(0.299, 0.587, 0.114));
  return luma;
}

}  // namespace

double MaskedPsnr(const Image& a, const Image& b, const Image& mask) {
  CheckPair(a, b, mask);
  const cv::Mat counted = CountedPixels(mask, a.width, a.height);
  cv::Mat diff;
  cv::absdiff(ToUnitDouble(a), ToUnitDouble(b), diff);
  diff = diff.mul(diff);
  const cv::Scalar sum = cv::sum(diff.setTo(0, counted == 0));
  const double n = static_cast<double>(cv::countNonZero(counted)) * diff.channels();
  const double mse = (sum[0] + sum[1] + sum[2] + sum[3]) / n;
  if (mse <= 0.0) return kMaxPsnrDb;
  return std::min(kMaxPsnrDb, -10.0 * std::log10(mse));
}

double MaskedSsim(const Image& a, const Image& b, const Image& mask) {
  CheckPair(a, b, mask);
  const cv::Mat counted = CountedPixels(mask, a.width, a.height);
  const cv::Mat x = Luma(ToUnitDouble(a)), y = Luma(ToUnitDouble(b));
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  auto blur = [](const cv::Mat& m) {
    cv::Mat out;
    cv::GaussianBlur(m, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
    return out;
  };
  const cv::Mat mx = blur(x), my = blur(y);
  const cv::Mat sxx = blur(x.mul(x)) - mx.mul(mx);
  const cv::Mat syy = blur(y.mul(y)) - my.mul(my);
  const cv::Mat sxy = blur(x.mul(y)) - mx.mul(my);
  cv::Mat numerator = (2 * mx.mul(my) + c1).mul(2 * sxy + c2);
  cv::Mat denominator = (mx.mul(mx) + my.mul(my) + c1).mul(sxx + syy + c2);
  cv::Mat ssim;
  cv::divide(numerator, denominator, ssim);
  return cv::mean(ssim, counted)[0];
}

Image UnionMask(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != 1 || b.channels != 1 ||
      a.type != PixelType::kUInt8 || b.type != PixelType::kUInt8)
    throw std::invalid_argument("UnionMask: masks must be 8-bit, 1-channel and of the same size");
  Image out(a.width, a.height, 1);
  for (std::size_t i = 0; i < out.data.size(); ++i)
    out.data[i] = (a.data[i] != 0 || b.data[i] != 0) ? 255 : 0;
  return out;
}

Image AbsoluteDifference(const Image& a, const Image& b) {
  CheckPair(a, b, {});
  cv::Mat diff;
  cv::absdiff(ToUnitDouble(a), ToUnitDouble(b), diff);
  if (diff.channels() > 1) cv::transform(diff, diff, cv::Matx13d(1.0 / 3, 1.0 / 3, 1.0 / 3));
  cv::Mat single;
  diff.convertTo(single, CV_32F);
  return ImageFromCvMat(single);
}

}  // namespace confluent
