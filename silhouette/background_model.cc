#include "silhouette/background_model.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/error.h"
#include "silhouette/classify_kernel.h"

namespace confluent {

namespace {

constexpr float kSpreadStep = 0.125f;  // grey levels per spread code
constexpr float kHighStep = 1.0f / 32.0f;

void CheckRgb8(const Image& image, const std::string& source, const char* what) {
  if (image.empty() || image.channels != 3 || image.type != PixelType::kUInt8)
    throw InputError(source, std::string(what) + " is not an 8-bit RGB image");
}

// Robust sensor-noise estimate of an 8-bit RGB image (Immerkaer 1996, with a median instead of
// the mean so that texture and edges do not inflate it): grey levels, averaged over channels.
double EstimateNoiseSigma(const Image& image) {
  const int w = image.width, h = image.height;
  if (w < 8 || h < 8) return 0.0;
  const std::uint8_t* p = image.data.data();
  const int step = std::max(1, std::min(w, h) / 256);
  double sum = 0;
  for (int c = 0; c < 3; ++c) {
    std::vector<int> responses;
    responses.reserve(static_cast<std::size_t>(w / step + 1) * (h / step + 1));
    for (int y = 1; y + 1 < h; y += step)
      for (int x = 1; x + 1 < w; x += step) {
        auto at = [&](int dx, int dy) { return static_cast<int>(p[((y + dy) * w + x + dx) * 3 + c]); };
        const int r = at(-1, -1) - 2 * at(0, -1) + at(1, -1) - 2 * at(-1, 0) + 4 * at(0, 0) - 2 * at(1, 0) +
                      at(-1, 1) - 2 * at(0, 1) + at(1, 1);
        responses.push_back(std::abs(r));
      }
    auto middle = responses.begin() + responses.size() / 2;
    std::nth_element(responses.begin(), middle, responses.end());
    // The kernel's response to unit Gaussian noise has standard deviation 6; median |N(0,1)| = 0.6745.
    sum += *middle / (6.0 * 0.6745);
  }
  return sum / 3.0;
}

// Largest absolute central difference over channels and both axes, grey levels per pixel.
std::vector<float> GradientMagnitude(const std::vector<float>& mean, int w, int h) {
  std::vector<float> gradient(static_cast<std::size_t>(w) * h, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int x0 = std::max(0, x - 1), x1 = std::min(w - 1, x + 1);
      const int y0 = std::max(0, y - 1), y1 = std::min(h - 1, y + 1);
      float g = 0;
      for (int c = 0; c < 3; ++c) {
        const float gx = (mean[(static_cast<std::size_t>(y) * w + x1) * 3 + c] - mean[(static_cast<std::size_t>(y) * w + x0) * 3 + c]) /
                         std::max(1, x1 - x0);
        const float gy = (mean[(static_cast<std::size_t>(y1) * w + x) * 3 + c] - mean[(static_cast<std::size_t>(y0) * w + x) * 3 + c]) /
                         std::max(1, y1 - y0);
        g = std::max(g, std::max(std::abs(gx), std::abs(gy)));
      }
      gradient[static_cast<std::size_t>(y) * w + x] = g;
    }
  return gradient;
}

// Median of a small array (modified in place).
template <typename T>
T Median(std::vector<T>* values) {
  auto middle = values->begin() + values->size() / 2;
  std::nth_element(values->begin(), middle, values->end());
  return *middle;
}

}  // namespace

void BackgroundModelOptions::Check() const {
  const std::string owner = "BackgroundModelOptions.";
  RequireOption(min_spread >= kSpreadStep && min_spread <= 30, owner + "min_spread", min_spread,
                "in [0.125, 30] grey levels");
  RequireOption(gradient_spread >= 0 && gradient_spread <= 2, owner + "gradient_spread", gradient_spread, "in [0, 2]");
  RequireOption(chroma_relative >= 0 && chroma_relative <= 0.5, owner + "chroma_relative", chroma_relative,
                "in [0, 0.5]");
  RequireOption(chroma_threshold > 0 && chroma_threshold <= 50, owner + "chroma_threshold", chroma_threshold,
                "in (0, 50]");
  RequireOption(brightness_threshold > 0 && brightness_threshold <= 50, owner + "brightness_threshold",
                brightness_threshold, "in (0, 50]");
  RequireOption(shadow_min_brightness >= 0 && shadow_min_brightness < 1, owner + "shadow_min_brightness",
                shadow_min_brightness, "in [0, 1)");
  RequireOption(highlight_max_brightness > 1 && highlight_max_brightness <= 8, owner + "highlight_max_brightness",
                highlight_max_brightness, "in (1, 8]");
  RequireOption(refine_frames >= 0 && refine_frames <= 1000, owner + "refine_frames", refine_frames, "in [0, 1000]");
  RequireOption(plate_weight > 0, owner + "plate_weight", plate_weight, "> 0");
  RequireOption(learned_frames >= 3 && learned_frames <= 1001, owner + "learned_frames", learned_frames,
                "in [3, 1001]");
}

BackgroundModel BackgroundModel::FromPlates(const std::vector<Image>& plates, const BackgroundModelOptions& options,
                                            const std::string& source) {
  options.Check();
  if (plates.empty()) throw InputError(source, "no background plate given");
  for (const Image& plate : plates) {
    CheckRgb8(plate, source, "background plate");
    if (plate.width != plates[0].width || plate.height != plates[0].height)
      throw InputError(source, "background plates differ in size (" + std::to_string(plate.width) + "x" +
                                   std::to_string(plate.height) + " vs " + std::to_string(plates[0].width) + "x" +
                                   std::to_string(plates[0].height) + ")");
  }
  BackgroundModel model;
  model.options_ = options;
  model.width_ = plates[0].width;
  model.height_ = plates[0].height;
  const std::size_t pixels = static_cast<std::size_t>(model.width_) * model.height_;
  const double n = static_cast<double>(plates.size());
  model.mean_.assign(pixels * 3, 0.0f);
  for (const Image& plate : plates)
    for (std::size_t i = 0; i < pixels * 3; ++i) model.mean_[i] += plate.data[i];
  for (float& value : model.mean_) value = static_cast<float>(value / n);

  double noise = 0;
  for (const Image& plate : plates) noise += EstimateNoiseSigma(plate);
  model.noise_sigma_ = noise / n;
  const std::vector<float> gradient = GradientMagnitude(model.mean_, model.width_, model.height_);
  // A frame's pixel differs from the mean by the frame's noise plus the mean's own noise.
  const double noise_variance = model.noise_sigma_ * model.noise_sigma_;
  model.spread_.assign(pixels, 0.0f);
  for (std::size_t i = 0; i < pixels; ++i) {
    double variance = noise_variance;
    if (plates.size() >= 2) {
      double sample = 0;
      for (int c = 0; c < 3; ++c) {
        double sum_sq = 0;
        for (const Image& plate : plates) {
          const double d = plate.data[i * 3 + c] - model.mean_[i * 3 + c];
          sum_sq += d * d;
        }
        sample += sum_sq / (n - 1);
      }
      sample /= 3;
      // The noise estimate acts as a prior worth two plates.
      variance = ((n - 1) * sample + 2 * noise_variance) / (n + 1);
    }
    const double g = options.gradient_spread * gradient[i];
    variance = variance * (1.0 + 1.0 / n) + g * g;
    model.spread_[i] = static_cast<float>(std::max(options.min_spread, std::sqrt(variance)));
  }
  model.Pack();
  return model;
}

BackgroundModel BackgroundModel::FromFrames(const std::vector<Image>& frames, const BackgroundModelOptions& options,
                                            const std::string& source, const std::vector<Image>& occupied,
                                            const Image& estimate) {
  options.Check();
  if (frames.size() < 3) throw InputError(source, "a learned background needs at least 3 frames");
  for (const Image& frame : frames) {
    CheckRgb8(frame, source, "frame");
    if (frame.width != frames[0].width || frame.height != frames[0].height)
      throw InputError(source, "frames differ in size");
  }
  if (!occupied.empty() && occupied.size() != frames.size())
    throw UsageError("BackgroundModel::FromFrames: one occupancy mask per frame is needed");
  for (const Image& mask : occupied)
    if (mask.width != frames[0].width || mask.height != frames[0].height || mask.channels != 1)
      throw InputError(source, "occupancy mask differs in size from the frames");
  if (!estimate.empty()) {
    CheckRgb8(estimate, source, "background estimate");
    if (estimate.width != frames[0].width || estimate.height != frames[0].height)
      throw InputError(source, "background estimate differs in size from the frames");
  }
  BackgroundModel model;
  model.options_ = options;
  model.width_ = frames[0].width;
  model.height_ = frames[0].height;
  const std::size_t pixels = static_cast<std::size_t>(model.width_) * model.height_;
  model.mean_.assign(pixels * 3, 0.0f);
  std::vector<float> deviation(pixels, 0.0f);
  std::vector<bool> guessed(pixels, false);  // too few free samples
  std::vector<int> values;
  std::vector<std::size_t> free;
  for (std::size_t i = 0; i < pixels; ++i) {
    free.clear();
    for (std::size_t k = 0; k < frames.size(); ++k)
      if (occupied.empty() || occupied[k].data[i] == 0) free.push_back(k);
    if (free.size() < static_cast<std::size_t>(kMinFreeSamples)) {
      guessed[i] = true;
      if (!estimate.empty()) {
        for (int c = 0; c < 3; ++c) model.mean_[i * 3 + c] = estimate.data[i * 3 + c];
        continue;
      }
      free.clear();
      for (std::size_t k = 0; k < frames.size(); ++k) free.push_back(k);
    }
    float mad_sum = 0;
    for (int c = 0; c < 3; ++c) {
      values.resize(free.size());
      for (std::size_t k = 0; k < free.size(); ++k) values[k] = frames[free[k]].data[i * 3 + c];
      const int median = Median(&values);
      model.mean_[i * 3 + c] = static_cast<float>(median);
      for (int& value : values) value = std::abs(value - median);
      mad_sum += static_cast<float>(Median(&values));
    }
    // MAD to standard deviation for Gaussian noise; at least half a level of quantisation.
    deviation[i] = std::max(0.5f, 1.4826f * mad_sum / 3.0f);
  }
  std::vector<float> sorted;
  for (std::size_t i = 0; i < pixels; ++i)
    if (!guessed[i] || occupied.empty()) sorted.push_back(deviation[i]);
  model.noise_sigma_ = sorted.empty() ? 1.0 : Median(&sorted);
  const std::vector<float> gradient = GradientMagnitude(model.mean_, model.width_, model.height_);
  model.spread_.assign(pixels, 0.0f);
  const float low = static_cast<float>(model.noise_sigma_), high = 2.0f * low;
  for (std::size_t i = 0; i < pixels; ++i) {
    // Pixels that the actor crossed often have an inflated deviation: bound it.
    const float sigma = guessed[i] && !occupied.empty() ? high : std::clamp(deviation[i], low, high);
    const float g = static_cast<float>(options.gradient_spread) * gradient[i];
    model.spread_[i] = std::max(static_cast<float>(options.min_spread), std::sqrt(sigma * sigma + g * g));
  }
  model.Pack();
  return model;
}

void BackgroundModel::Pack() {
  const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
  packed_.assign(pixels * 6, 0);
  std::uint8_t* planes[6];
  for (int k = 0; k < 6; ++k) planes[k] = packed_.data() + k * pixels;
  const double tau_b = options_.brightness_threshold;
  for (std::size_t i = 0; i < pixels; ++i) {
    double norm_sq = 0;
    for (int c = 0; c < 3; ++c) {
      // A black mean would make brightness distortion undefined: keep at least one level.
      const int level = std::clamp(static_cast<int>(std::lround(mean_[i * 3 + c])), 1, 255);
      planes[c][i] = static_cast<std::uint8_t>(level);
      norm_sq += static_cast<double>(level) * level;
    }
    const double sigma = spread_[i] * threshold_scale_;
    const int spread_code = std::clamp(static_cast<int>(std::lround(sigma / kSpreadStep)), 1, 255);
    planes[3][i] = static_cast<std::uint8_t>(spread_code);
    const double sigma_q = spread_code * kSpreadStep;
    const double relative = tau_b * sigma_q / std::sqrt(norm_sq);  // brightness noise as a fraction
    const double low = std::clamp(std::min(options_.shadow_min_brightness, 1.0 - relative), 0.0, 1.0);
    const double high = std::max(options_.highlight_max_brightness, 1.0 + relative);
    planes[4][i] = static_cast<std::uint8_t>(std::clamp(static_cast<int>(std::floor(low * 255.0)), 0, 255));
    planes[5][i] = static_cast<std::uint8_t>(std::clamp(static_cast<int>(std::ceil((high - 1.0) / kHighStep)), 0, 255));
  }
}

Image BackgroundModel::Classify(const Image& frame) const { return Classify(frame, nullptr); }

ClassifyParams BackgroundModel::Params() const {
  ClassifyParams params;
  const float tau_c = static_cast<float>(options_.chroma_threshold);
  params.chroma_threshold_sq = tau_c * tau_c;
  params.chroma_relative_sq = static_cast<float>(options_.chroma_relative * options_.chroma_relative);
  params.spread_step = kSpreadStep;
  params.high_step = kHighStep;
  return params;
}

// Background, shadow or highlight of a pixel the classifier did not call foreground: its
// brightness change along the mean colour, in grey levels, against the noise.
PixelClass BackgroundModel::BrightnessClass(const Image& frame, std::size_t i, const ClassifyPlanes& planes) const {
  const float m[3] = {static_cast<float>(planes.mean_r[i]), static_cast<float>(planes.mean_g[i]),
                      static_cast<float>(planes.mean_b[i])};
  const std::uint8_t* v = &frame.data[i * 3];
  const float norm_sq = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
  const float dot = v[0] * m[0] + v[1] * m[1] + v[2] * m[2];
  const float change = (dot - norm_sq) / std::sqrt(norm_sq);
  const float sigma = planes.spread[i] * kSpreadStep;
  if (change < -options_.brightness_threshold * sigma) return PixelClass::kShadow;
  if (change > options_.brightness_threshold * sigma) return PixelClass::kHighlight;
  return PixelClass::kBackground;
}

Image BackgroundModel::Classify(const Image& frame, Image* labels) const {
  if (frame.width != width_ || frame.height != height_ || frame.channels != 3 || frame.type != PixelType::kUInt8)
    std::abort();  // internal invariant: callers check sizes and convert to 8-bit RGB
  Image mask(width_, height_, 1);
  const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
  const ClassifyPlanes planes = PlanesOf(packed_.data(), pixels);
  ClassifyPixels(frame.data.data(), planes, pixels, Params(), mask.data.data());
  if (labels != nullptr) {
    *labels = Image(width_, height_, 1);
    for (std::size_t i = 0; i < pixels; ++i)
      labels->data[i] = static_cast<std::uint8_t>(mask.data[i] ? PixelClass::kForeground
                                                                : BrightnessClass(frame, i, planes));
  }
  return mask;
}

PixelClass BackgroundModel::ClassOf(const Image& frame, int x, int y) const {
  if (frame.width != width_ || frame.height != height_ || frame.channels != 3 || frame.type != PixelType::kUInt8 ||
      x < 0 || y < 0 || x >= width_ || y >= height_)
    std::abort();  // internal invariant, as Classify
  const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
  const std::size_t i = static_cast<std::size_t>(y) * width_ + x;
  const ClassifyPlanes planes = PlanesOf(packed_.data(), pixels);
  const std::uint8_t mean[3] = {planes.mean_r[i], planes.mean_g[i], planes.mean_b[i]};
  if (ClassifyPixelReference(&frame.data[i * 3], mean, planes.spread[i], planes.low[i], planes.high[i], Params()))
    return PixelClass::kForeground;
  return BrightnessClass(frame, i, planes);
}

void BackgroundModel::Adapt(const std::vector<Image>& frames) {
  if (empty()) return;
  const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
  std::vector<float> sum(pixels * 3, 0.0f), sum_sq(pixels, 0.0f);
  std::vector<std::uint16_t> count(pixels, 0);
  std::vector<const Image*> used;
  for (const Image& frame : frames) {
    if (frame.width != width_ || frame.height != height_ || frame.channels != 3 || frame.type != PixelType::kUInt8)
      continue;
    used.push_back(&frame);
    Image labels;
    Classify(frame, &labels);
    for (std::size_t i = 0; i < pixels; ++i) {
      if (labels.data[i] != static_cast<std::uint8_t>(PixelClass::kBackground)) continue;
      float d2 = 0;
      for (int c = 0; c < 3; ++c) {
        const float value = frame.data[i * 3 + c];
        sum[i * 3 + c] += value;
        const float d = value - mean_[i * 3 + c];
        d2 += d * d;
      }
      sum_sq[i] += d2 / 3.0f;
      ++count[i];
    }
  }
  if (used.empty()) return;
  const float w0 = static_cast<float>(options_.plate_weight);
  for (std::size_t i = 0; i < pixels; ++i) {
    if (count[i] == 0) continue;
    const float n = count[i];
    float shift_sq = 0;
    for (int c = 0; c < 3; ++c) {
      const float updated = (w0 * mean_[i * 3 + c] + sum[i * 3 + c]) / (w0 + n);
      const float shift = updated - mean_[i * 3 + c];
      shift_sq += shift * shift / 3.0f;
      mean_[i * 3 + c] = updated;
    }
    // Spread: the plate's spread as a prior, plus the frames' deviations from the new mean.
    const float frame_var = std::max(0.0f, sum_sq[i] / n - shift_sq);
    const float variance = (w0 * spread_[i] * spread_[i] + n * frame_var) / (w0 + n);
    spread_[i] = std::max(static_cast<float>(options_.min_spread), std::sqrt(variance));
  }
  Pack();
  if (options_.auto_thresholds) {
    std::vector<Image> copies;
    for (const Image* frame : used) copies.push_back(*frame);
    AutoThreshold(copies);
  }
}

void BackgroundModel::AutoThreshold(const std::vector<Image>& frames) {
  if (empty()) return;
  // Chromaticity distortion of background pixels, in spreads, follows a Rayleigh distribution
  // (a 2-D Gaussian residual orthogonal to the mean colour) whose lower quartile is 0.7585.
  // Most pixels of a frame are background, so the lower quartile of all pixels' distortions
  // measures how far the actual noise exceeds the model's.
  std::vector<float> distortions;
  const float r2 = static_cast<float>(options_.chroma_relative * options_.chroma_relative);
  for (const Image& frame : frames) {
    if (frame.width != width_ || frame.height != height_ || frame.channels != 3 || frame.type != PixelType::kUInt8)
      continue;
    for (int y = 1; y < height_; y += 3)
      for (int x = 1; x < width_; x += 3) {
        const std::size_t i = static_cast<std::size_t>(y) * width_ + x;
        const std::uint8_t* v = &frame.data[i * 3];
        const float* m = &mean_[i * 3];
        const float norm_sq = std::max(3.0f, m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        const float dot = v[0] * m[0] + v[1] * m[1] + v[2] * m[2];
        const float value_sq = float(v[0]) * v[0] + float(v[1]) * v[1] + float(v[2]) * v[2];
        const float cd_sq = std::max(0.0f, value_sq - dot * dot / norm_sq);
        const float sigma_sq = spread_[i] * spread_[i] + r2 * dot * dot / norm_sq;
        distortions.push_back(std::sqrt(cd_sq / sigma_sq));
      }
  }
  if (distortions.size() < 100) return;
  auto quartile = distortions.begin() + distortions.size() / 4;
  std::nth_element(distortions.begin(), quartile, distortions.end());
  threshold_scale_ = std::clamp(static_cast<double>(*quartile) / 0.7585, 0.75, 6.0);
  Pack();
}

Image BackgroundModel::MeanImage() const {
  Image image(width_, height_, 3);
  for (std::size_t i = 0; i < image.data.size(); ++i)
    image.data[i] = static_cast<std::uint8_t>(std::clamp(static_cast<int>(std::lround(mean_[i])), 0, 255));
  return image;
}

Eigen::Vector3f BackgroundModel::MeanAt(int x, int y) const {
  const std::size_t at = (static_cast<std::size_t>(y) * width_ + x) * 3;
  return {mean_[at], mean_[at + 1], mean_[at + 2]};
}

}  // namespace confluent
