#include "render/composite.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"

namespace confluent {

Image CompositeOverBackground(const RenderResult& rendered, const Image& background, const std::string& background_name,
                              double edge_softness_px) {
  const Image& color = rendered.color;
  if (rendered.silhouette.width != color.width || rendered.silhouette.height != color.height)
    throw InputError(background_name, "the render has no silhouette to composite with");
  if (background.width != color.width || background.height != color.height)
    throw InputError(background_name, "background is " + std::to_string(background.width) + "x" +
                                          std::to_string(background.height) + ", the view " +
                                          std::to_string(color.width) + "x" + std::to_string(color.height));
  if (background.channels != 3 || background.type != PixelType::kUInt8 || color.channels != 3 ||
      color.type != PixelType::kUInt8)
    throw InputError(background_name, "background and render must both be RGB 8-bit");
  if (!(edge_softness_px >= 0.0) || !std::isfinite(edge_softness_px))
    throw UsageError("edge softness must be a finite number of pixels >= 0");
  Image out = background;
  const std::size_t pixels = rendered.silhouette.data.size();
  if (edge_softness_px == 0.0) {
    for (std::size_t p = 0; p < pixels; ++p)
      if (rendered.silhouette.data[p] != 0) std::copy_n(color.data.begin() + 3 * p, 3, out.data.begin() + 3 * p);
    return out;
  }
  // Alpha: the blurred silhouette. Colour outside the silhouette: normalised convolution of the
  // covered colours (their Gaussian-weighted mean nearby).
  cv::Mat coverage;
  AsCvMat(rendered.silhouette).convertTo(coverage, CV_32F, 1.0 / 255.0);
  cv::Mat premultiplied;
  AsCvMat(color).convertTo(premultiplied, CV_32FC3);
  const std::vector<cv::Mat> planes = {coverage, coverage, coverage};
  cv::Mat coverage3;
  cv::merge(planes, coverage3);
  premultiplied = premultiplied.mul(coverage3);
  cv::Mat alpha, blurred;
  cv::GaussianBlur(coverage, alpha, cv::Size(0, 0), edge_softness_px);
  cv::GaussianBlur(premultiplied, blurred, cv::Size(0, 0), edge_softness_px);
  const float* a = alpha.ptr<float>();
  const float* b = blurred.ptr<float>();
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!(a[p] > 1e-3f)) continue;
    const bool covered = rendered.silhouette.data[p] != 0;
    for (int c = 0; c < 3; ++c) {
      const float colour = covered ? static_cast<float>(color.data[3 * p + c]) : b[3 * p + c] / a[p];
      const float value = a[p] * colour + (1.0f - a[p]) * static_cast<float>(background.data[3 * p + c]);
      out.data[3 * p + c] = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  }
  return out;
}

}  // namespace confluent
