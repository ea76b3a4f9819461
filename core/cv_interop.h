#pragma once
// Zero-copy bridges between confluent::Image and cv::Mat.
// INTERNAL: include only from .cc files (public headers stay free of OpenCV types).

#include <opencv2/core.hpp>

#include "core/image.h"

namespace confluent {

// OpenCV element type matching the image's pixel type and channels.
int CvTypeOf(const Image& image);

// A cv::Mat header that shares `image`'s memory (channels keep RGB order, not BGR).
cv::Mat AsCvMat(Image& image);
cv::Mat AsCvMat(const Image& image);  // treat as read-only

// Deep copy of a cv::Mat (8U, 16U or 32F, 1-4 channels) into an Image, channel order kept.
Image ImageFromCvMat(const cv::Mat& mat);

}  // namespace confluent
