#pragma once
// Per-pixel colour background model with brightness and chromaticity distortion
// (Horprasert, Harwood and Davis 1999): shadows and highlights of the background are not
// foreground. Built from clean plates or learned from the video (temporal median).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"
#include "silhouette/classify_kernel.h"

namespace confluent {

// Settings of the background model and its classifier. Distortions are measured in units of
// the per-pixel spread (a noise standard deviation in 8-bit grey levels).
struct BackgroundModelOptions {
  // Floor on the per-pixel spread, grey levels.
  double min_spread = 1.0;
  // Spread added per grey level per pixel of plate gradient (sub-pixel jitter, blur, resampling).
  double gradient_spread = 0.25;
  // Chromaticity tolerance proportional to brightness (tinted shadows, compression), as a
  // fraction of the pixel's brightness (norm of its RGB vector).
  double chroma_relative = 0.01;
  // Chromaticity distortion above this many spreads is foreground.
  double chroma_threshold = 4.5;
  // A brightness change of more than this many spreads may be foreground (see below).
  double brightness_threshold = 4.5;
  // Darker than this fraction of the background brightness is foreground; between it and 1 a
  // chromatically consistent pixel is a shadow (background).
  double shadow_min_brightness = 0.4;
  // Brighter than this factor is foreground; between 1 and it a pixel is a highlight.
  double highlight_max_brightness = 1.3;
  // Scale the thresholds per camera from the histogram of chromaticity distortions of the
  // first frames, so that the background's distortions match the noise model.
  bool auto_thresholds = true;
  // Number of first frames whose background-classified pixels refine mean and spread (plates).
  int refine_frames = 3;
  // Weight, in frames, of the plate statistics against the refining frames.
  double plate_weight = 2.0;
  // Frames sampled evenly over the video for a learned (temporal median) background.
  int learned_frames = 31;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// Per-pixel classes of BackgroundModel::Classify (with labels).
enum class PixelClass : std::uint8_t { kBackground = 0, kShadow = 1, kHighlight = 2, kForeground = 3 };

// Per-pixel mean colour and spread of a static background, plus thresholds. State across
// frames (refinement, thresholds), hence a class. Images are 8-bit RGB.
class BackgroundModel {
 public:
  BackgroundModel() = default;

  // Model from one or more clean plates of the same size (8-bit RGB). With one plate the spread
  // comes from the plate's noise level (Immerkaer 1996) and gradients; with several, from the
  // per-pixel temporal variance. Throws InputError(`source`) if the plates differ in size or
  // are not 8-bit RGB.
  static BackgroundModel FromPlates(const std::vector<Image>& plates, const BackgroundModelOptions& options,
                                    const std::string& source = {});

  // Learned background: per-pixel temporal median of `frames` (8-bit RGB, same size; at least
  // 3), spread from the per-pixel median absolute deviation. Throws InputError(`source`).
  // With `occupied` (one 1-channel mask per frame, nonzero where the actor may be), only the
  // free samples of a pixel count; a pixel free in fewer than kMinFreeSamples frames takes the
  // colour of `estimate` (8-bit RGB of the frames' size; without it, the median of all samples)
  // and a doubled spread.
  static constexpr int kMinFreeSamples = 2;
  static BackgroundModel FromFrames(const std::vector<Image>& frames, const BackgroundModelOptions& options,
                                    const std::string& source = {}, const std::vector<Image>& occupied = {},
                                    const Image& estimate = {});

  // Refines mean and spread with the pixels of `frames` that the current model classifies as
  // background (not shadow or highlight), then (if options.auto_thresholds) rescales the
  // thresholds from the chromaticity-distortion histogram. Frames of another size are ignored.
  void Adapt(const std::vector<Image>& frames);

  // Rescales the thresholds from the distortion histogram of `frames` without refining.
  void AutoThreshold(const std::vector<Image>& frames);

  // Foreground mask (0/255, 1 channel) of an 8-bit RGB frame of the model's size.
  // Aborts on a size mismatch (callers check, see SilhouetteExtractor).
  Image Classify(const Image& frame) const;
  // As Classify, writing a PixelClass per pixel into `labels` (1 channel) as well.
  Image Classify(const Image& frame, Image* labels) const;
  // The class of one pixel (x, y) of `frame`, as Classify's labels give it.
  PixelClass ClassOf(const Image& frame, int x, int y) const;

  int width() const { return width_; }
  int height() const { return height_; }
  bool empty() const { return width_ == 0; }
  // Mean background colour as an 8-bit RGB image.
  Image MeanImage() const;
  // Mean background colour (RGB, 8-bit scale) of pixel (x, y).
  Eigen::Vector3f MeanAt(int x, int y) const;
  // Estimated sensor noise (grey levels) of the source plates or frames.
  double noise_sigma() const { return noise_sigma_; }
  // Factor by which auto thresholding scaled the spreads (1 = the noise model fits).
  double threshold_scale() const { return threshold_scale_; }
  const BackgroundModelOptions& options() const { return options_; }

 private:
  // Rebuilds the packed per-pixel classifier parameters from mean_ and spread_.
  void Pack();
  ClassifyParams Params() const;
  PixelClass BrightnessClass(const Image& frame, std::size_t pixel, const ClassifyPlanes& planes) const;

  BackgroundModelOptions options_;
  int width_ = 0;
  int height_ = 0;
  double noise_sigma_ = 0.0;
  double threshold_scale_ = 1.0;
  std::vector<float> mean_;    // 3 per pixel
  std::vector<float> spread_;  // 1 per pixel, grey levels
  // Six planes of one byte per pixel: mean R, G, B (8-bit), spread code, low and high
  // brightness bounds (see ClassifyPlanes in classify_kernel.h).
  std::vector<std::uint8_t> packed_;
};

}  // namespace confluent
