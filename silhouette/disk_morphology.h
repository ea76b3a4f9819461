#pragma once
// INTERNAL: include only from .cc files (it uses OpenCV types).
//
// Morphology of 0/255 masks by a disk, worked only in the box around the mask's nonzero pixels
// (grown by the radius): the result is the same as over the whole image, at a cost that follows
// the actor's size rather than the image's, which matters for the large radii of the multi-view
// correction (a 83-pixel disk at 1024 pixels of width).

#include <opencv2/core.hpp>

namespace confluent {

// The disk of the given radius (an ellipse in a (2r+1)^2 box), as cv::getStructuringElement.
cv::Mat Disk(int radius);

// A margin given per 1000 pixels of width, in pixels of this image (at least 1 when positive).
int ScaledRadius(double per_1000, int width);

// cv::dilate by Disk(radius) (outside the image counts as empty).
cv::Mat DilateByDisk(const cv::Mat& mask, int radius);
// cv::erode by Disk(radius) with OpenCV's default border (outside the image counts as set).
cv::Mat ErodeByDisk(const cv::Mat& mask, int radius);
// Closing by Disk(radius) with outside the image empty (cv::MORPH_CLOSE, BORDER_CONSTANT 0).
cv::Mat CloseByDisk(const cv::Mat& mask, int radius);

}  // namespace confluent
