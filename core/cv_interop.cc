#include "core/cv_interop.h"

#include <cstdlib>

namespace confluent {

int CvTypeOf(const Image& image) {
  const int depth = image.type == PixelType::kUInt8 ? CV_8U : image.type == PixelType::kUInt16 ? CV_16U : CV_32F;
  return CV_MAKETYPE(depth, image.channels);
}

cv::Mat AsCvMat(Image& image) {
  return cv::Mat(image.height, image.width, CvTypeOf(image), image.data.data(), image.row_bytes());
}

cv::Mat AsCvMat(const Image& image) {
  return cv::Mat(image.height, image.width, CvTypeOf(image), const_cast<std::uint8_t*>(image.data.data()),
                 image.row_bytes());
}

Image ImageFromCvMat(const cv::Mat& mat) {
  PixelType type = PixelType::kUInt8;
  switch (mat.depth()) {
    case CV_8U: type = PixelType::kUInt8; break;
    case CV_16U: type = PixelType::kUInt16; break;
    case CV_32F: type = PixelType::kFloat32; break;
    default: std::abort();  // internal invariant: callers convert first
  }
  Image image(mat.cols, mat.rows, mat.channels(), type);
  cv::Mat view = AsCvMat(image);
  mat.copyTo(view);
  return image;
}

}  // namespace confluent
