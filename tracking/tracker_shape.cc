// The Tracker's shape learned over the first frames (TrackerOptions::shape_samples).

#include <string>
#include <vector>

#include "core/statistics.h"
#include "tracking/tracker.h"

namespace confluent {

namespace {

// `base` with each girth, cross-section and skirt parameter the median over `shapes` (not
// empty). The skeleton stays `base`'s: its lengths, and the girths of the torso pieces, which set
// how far apart the shoulders and the hips sit (RestPositions).
BodyShape MedianGirthsAndSections(const BodyTemplate& body, const BodyShape& base, const std::vector<BodyShape>& shapes) {
  auto median_of = [&](auto value_of) {
    std::vector<double> values;
    for (const BodyShape& shape : shapes) values.push_back(value_of(shape));
    return Median(std::move(values));
  };
  BodyShape median = base;
  for (int s = 0; s < kNumBodySegments; ++s) {
    median.girth_scale[s] = median_of([s](const BodyShape& b) { return b.girth_scale[s]; });
    median.depth_scale[s] = median_of([s](const BodyShape& b) { return b.depth_scale[s]; });
    median.taper_scale[s] = median_of([s](const BodyShape& b) { return b.taper_scale[s]; });
    median.depth_offset[s] = median_of([s](const BodyShape& b) { return b.depth_offset[s]; });
    median.mid_bulge[s] = median_of([s](const BodyShape& b) { return b.mid_bulge[s]; });
  }
  for (int joint : {kJointLeftShoulder, kJointRightShoulder, kJointLeftHip, kJointRightHip}) {
    const int torso = body.offset_segment()[joint];
    median.girth_scale[torso] = base.girth_scale[torso];
  }
  median.skirt_length_m = median_of([](const BodyShape& b) { return b.skirt_length_m; });
  median.skirt_flare_m = median_of([](const BodyShape& b) { return b.skirt_flare_m; });
  return median;
}

}  // namespace

void Tracker::LearnShapeOverFirstFrames(const std::vector<Image>& masks, const std::vector<bool>& use,
                                        const SilhouetteObservations& observations, TrackedFrame* result) {
  if (!later_masks_ || options_.shape_samples <= 1) return;
  // The frames after the first, tracked ahead on a copy with the first frame's shape; the first
  // frame and every shape_sample_every-th one after it are the samples.
  struct Sample {
    std::vector<Image> masks;
    TemplatePose pose;
  };
  std::vector<Sample> samples;
  Tracker ahead = *this;
  ahead.later_masks_ = nullptr;
  const int first = result->frame;
  for (int k = 1; k <= (options_.shape_samples - 1) * options_.shape_sample_every; ++k) {
    std::vector<Image> later = later_masks_(first + k);
    if (later.empty()) break;
    const TrackedFrame tracked = ahead.Track(first + k, later);
    if (k % options_.shape_sample_every == 0 && !IsRepeatedFrame(tracked))
      samples.push_back({std::move(later), tracked.pose});
  }
  if (samples.empty()) return;  // the first frame alone: its own fit's shape stands
  // Shape and pose fitted freely on each sample (the per-frame fit's shape priors, not the first
  // fit's pull towards human proportions), the first frame's included.
  SilhouetteFitOptions free_shape = options_.fit;
  free_shape.fit_shape = true;
  free_shape.fit_skirt = shape_.skirt_length_m > 0.0;  // no skirt grows on a body fitted without one
  // The first frame's fits keep the pulls towards rest angles that Initialize chose.
  SilhouetteFitOptions first_frame_fit = options_.fit;
  first_frame_fit.rest_prior_scale = init_rest_prior_scale_;
  std::vector<BodyShape> shapes;
  auto fit_shape = [&](const SilhouetteObservations& sample_observations, const TemplatePose& pose,
                       double rest_prior_scale) {
    BodyShape shape = shape_;
    TemplatePose fitted = pose;
    SilhouetteFitOptions fit = free_shape;
    fit.rest_prior_scale = rest_prior_scale;
    FitTemplateToSilhouettes(body_, sample_observations, fit, &shape, &fitted, &pose);
    shapes.push_back(shape);
  };
  fit_shape(observations, result->pose, init_rest_prior_scale_);
  for (const Sample& sample : samples) {
    std::vector<std::string> flags;
    const std::vector<bool> sample_use = UsableCameras(sample.masks, &flags);
    fit_shape(Observations(sample.masks, sample_use), sample.pose, options_.fit.rest_prior_scale);
  }
  // The first frame again with the learned shape, from its pose.
  // The skeleton stays the first fit's: silhouettes place a joint along its limb poorly, and the
  // free fits' lengths moved the joints (builtin's 0.44 -> 0.97 cm mean error at 1024x768), their
  // torso girths the shoulders (1.2 cm apart each on builtin, fitted at 512 pixels across).
  shape_ = MedianGirthsAndSections(body_, shape_, shapes);
  const TemplatePose first_pose = result->pose;
  result->fit = FitTemplateToSilhouettes(body_, observations, first_frame_fit, &shape_, &result->pose, &first_pose);
  Evaluate(shape_, masks, use, result);
  result->flags.push_back("shape:" + std::to_string(shapes.size()));
  RestartHistoryAt(*result);
}

}  // namespace confluent
