#include "silhouette/multiview.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <opencv2/imgproc.hpp>

#include "core/statistics.h"
#include "calib/rig_check.h"
#include "core/cv_interop.h"
#include "core/error.h"
#include "silhouette/disk_morphology.h"

namespace confluent {

void MultiViewOptions::Check() const {
  const std::string owner = "MultiViewOptions.";
  RequireOption(grid_resolution >= 16 && grid_resolution <= 512, owner + "grid_resolution", grid_resolution,
                "in [16, 512]");
  RequireOption(tolerated_rejections >= -1 && tolerated_rejections <= 4, owner + "tolerated_rejections",
                tolerated_rejections, "in [-1, 4]");
  RequireOption(ghost_margin >= 0 && ghost_margin <= 100, owner + "ghost_margin", ghost_margin, "in [0, 100]");
  RequireOption(hole_margin >= 0 && hole_margin <= 100, owner + "hole_margin", hole_margin, "in [0, 100]");
  RequireOption(hole_close >= 0 && hole_close <= 200, owner + "hole_close", hole_close, "in [0, 200]");
  RequireOption(claim_margin >= 0 && claim_margin <= 100, owner + "claim_margin", claim_margin, "in [0, 100]");
  RequireOption(min_confidence >= 0 && min_confidence <= 1, owner + "min_confidence", min_confidence, "in [0, 1]");
  RequireOption(max_hull_volume_m3 >= 0, owner + "max_hull_volume_m3", max_hull_volume_m3, ">= 0");
  RequireOption(threads >= 1, owner + "threads", threads, ">= 1");
}

namespace {

// The number of cameras with a mask; throws InputError naming a camera whose mask differs in
// size from its calibration.
int CountMasks(const Rig& rig, const std::vector<Image>& masks) {
  int with_mask = 0;
  for (int c = 0; c < rig.size(); ++c) {
    const Image& mask = masks[c];
    if (mask.empty()) continue;
    if (mask.width != rig.cameras[c].width || mask.height != rig.cameras[c].height || mask.channels != 1)
      throw InputError(rig.cameras[c].name, "mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                                                " but the calibration says " + std::to_string(rig.cameras[c].width) +
                                                "x" + std::to_string(rig.cameras[c].height));
    ++with_mask;
  }
  return with_mask;
}

// Each camera's projected tolerant hull of the others (one camera's hole does not carve it).
// Cameras without a mask, or with an empty one (the actor is in every camera's view), constrain
// nothing: a full mask. `carving` and `hull_options` receive what was carved with.
std::vector<Image> ToleratedHulls(const Rig& rig, const std::vector<Image>& masks, int with_mask,
                                  const MultiViewOptions& options, std::vector<Image>* carving,
                                  VisualHullOptions* hull_options, HullUnderside* underside) {
  const int n = rig.size();
  carving->assign(n, Image());
  for (int c = 0; c < n; ++c) {
    (*carving)[c] = masks[c];
    if ((*carving)[c].empty() || cv::countNonZero(AsCvMat((*carving)[c])) == 0) {
      (*carving)[c] = Image(rig.cameras[c].width, rig.cameras[c].height, 1);
      std::fill((*carving)[c].data.begin(), (*carving)[c].data.end(), 255);
    }
  }
  hull_options->grid_resolution = options.grid_resolution;
  hull_options->threads = options.threads;
  hull_options->tolerated_rejections =
      options.tolerated_rejections >= 0 ? options.tolerated_rejections : (with_mask - 1 >= 4 ? 1 : 0);
  std::vector<Image> projected;
  VisualHullConsistency(rig, *carving, {}, *hull_options, &projected, underside);
  return projected;
}

// `hull` grown by the ghost margin: mask pixels outside it are ghosts.
cv::Mat NearHull(const cv::Mat& hull, const MultiViewOptions& options) {
  const int radius = ScaledRadius(options.ghost_margin, hull.cols);
  return radius > 0 ? DilateByDisk(hull, radius) : hull;
}

}  // namespace

std::vector<ViewConsistency> CheckMultiView(const Rig& rig, std::vector<Image>* masks, const std::vector<bool>& correct,
                                            const MultiViewOptions& options, std::vector<Image>* hulls,
                                            std::vector<Image>* strict_hulls, HullUnderside* underside) {
  options.Check();
  HullUnderside own_underside;  // the volume is needed even when the caller wants no underside
  if (underside == nullptr) underside = &own_underside;
  *underside = HullUnderside();
  const int n = rig.size();
  if (static_cast<int>(masks->size()) != n) throw UsageError("CheckMultiView: one mask (or an empty image) per camera");
  if (!correct.empty() && static_cast<int>(correct.size()) != n)
    throw UsageError("CheckMultiView: one correction switch per camera");
  std::vector<ViewConsistency> result(n);
  if (hulls != nullptr) hulls->assign(n, Image());
  if (strict_hulls != nullptr) strict_hulls->assign(n, Image());
  const int with_mask = CountMasks(rig, *masks);
  if (with_mask < 3) {
    for (ViewConsistency& view : result) view.explained = view.covered = view.confidence = 1;
    return result;
  }
  // Ghosts are judged against a tolerant hull (one camera's hole does not carve it); coverage and
  // holes against a strict one (tighter where the silhouettes have concavities) carved by the
  // cameras whose masks that hull explains (a shifted mask would carve it away).
  std::vector<Image> carving, strict;
  VisualHullOptions hull_options;
  std::vector<Image> projected = ToleratedHulls(rig, *masks, with_mask, options, &carving, &hull_options, underside);
  std::vector<cv::Mat> near_hulls(n);
  std::vector<double> explained(n, 1.0), explained_area(n, 0.0), explained_list;
  for (int c = 0; c < n; ++c) {
    if ((*masks)[c].empty()) continue;
    near_hulls[c] = NearHull(AsCvMat(projected[c]), options);
    const cv::Mat m = AsCvMat((*masks)[c]);
    cv::Mat both;
    cv::bitwise_and(m, near_hulls[c], both);
    const double area = cv::countNonZero(m);
    explained_area[c] = cv::countNonZero(both);
    explained[c] = area > 0 ? explained_area[c] / area : 0.0;
    explained_list.push_back(explained[c]);
  }
  // The hull's own coarseness leaves every camera's thin parts a little unexplained (a small
  // performer at a low resolution): a camera is judged against the frame's typical camera.
  const double typical_explained = std::max(0.5, Median(explained_list));
  std::vector<Image> strict_carving = carving;
  bool excluded = false;
  for (int c = 0; c < n; ++c)
    if (!(*masks)[c].empty() && explained[c] < 0.9 * typical_explained) {
      std::fill(strict_carving[c].data.begin(), strict_carving[c].data.end(), 255);
      excluded = true;
    }
  if (hull_options.tolerated_rejections > 0 || excluded) {
    hull_options.tolerated_rejections = 0;
    VisualHullConsistency(rig, strict_carving, {}, hull_options, &strict);
  } else {
    strict = projected;
  }

  std::vector<double> covered_list;
  for (int c = 0; c < n; ++c) {
    Image& mask = (*masks)[c];
    if (mask.empty()) continue;
    const int width = mask.width;
    const cv::Mat hull = AsCvMat(projected[c]);
    const cv::Mat& near_hull = near_hulls[c];
    const cv::Mat m = AsCvMat(mask);
    const double area = cv::countNonZero(m);
    const cv::Mat tight = AsCvMat(strict[c]);
    const double hull_area = cv::countNonZero(tight);
    cv::Mat both;
    cv::bitwise_and(m, tight, both);
    const double covered_area = cv::countNonZero(both);
    ViewConsistency& view = result[c];
    view.explained = explained[c];
    // An empty strict hull (some camera sees nothing) leaves nothing to cover.
    view.covered = hull_area > 0 ? covered_area / hull_area : 1.0;
    covered_list.push_back(view.covered);
    if (!correct.empty() && correct[c] && cv::countNonZero(hull) > 0) {
      // Ghosts: the mask where no other camera's hull comes near.
      cv::Mat corrected;
      cv::bitwise_and(m, near_hull, corrected);
      view.removed = static_cast<int>(area - explained_area[c]);
      // Holes: deep inside the hull and enclosed by the mask (its closing).
      const int deep = ScaledRadius(options.hole_margin, width), close = ScaledRadius(options.hole_close, width);
      const cv::Mat inner = deep > 0 ? ErodeByDisk(tight, deep) : tight;
      const cv::Mat closed = close > 0 ? CloseByDisk(corrected, close) : corrected;
      cv::Mat fill;
      cv::bitwise_and(inner, closed, fill);
      const double before = cv::countNonZero(corrected);
      cv::bitwise_or(corrected, fill, corrected);
      view.added = static_cast<int>(cv::countNonZero(corrected) - before);
      mask = ImageFromCvMat(corrected);
    }
  }
  // A hull is larger than the silhouette (concavities, few cameras): coverage counts relative to
  // the frame's typical camera.
  const double typical = covered_list.empty() ? 1.0 : std::max(0.5, Median(covered_list));
  // Masks can agree with each other and still hold background: then the hull is no person's.
  const double volume = underside->volume_m3;
  const double plausible = options.max_hull_volume_m3 > 0 && volume > options.max_hull_volume_m3
                               ? options.max_hull_volume_m3 / volume
                               : 1.0;
  for (int c = 0; c < n; ++c) {
    if ((*masks)[c].empty()) continue;
    ViewConsistency& view = result[c];
    view.hull_volume_m3 = volume;
    view.confidence = view.explained <= 0 ? 0.0
                                          : plausible * std::clamp(std::min(view.explained / typical_explained,
                                                                            view.covered / typical),
                                                                   0.0, 1.0);
  }
  for (int c = 0; c < n; ++c) {
    if ((*masks)[c].empty()) continue;
    if (strict_hulls != nullptr) (*strict_hulls)[c] = strict[c];
    if (hulls != nullptr) (*hulls)[c] = std::move(projected[c]);
  }
  return result;
}

std::vector<int> RemoveRefinementsTheOthersDoNotShare(const Rig& rig, const std::vector<Image>& before,
                                                      const std::vector<bool>& refined, const MultiViewOptions& options,
                                                      std::vector<Image>* masks) {
  const std::size_t n = masks->size();
  if (static_cast<int>(n) != rig.size() || before.size() != n || refined.size() != n)
    throw UsageError("RemoveRefinementsTheOthersDoNotShare: one mask, one mask before and one switch per camera");
  for (std::size_t c = 0; c < n; ++c)
    if (refined[c] && (before[c].width != (*masks)[c].width || before[c].height != (*masks)[c].height))
      throw UsageError("RemoveRefinementsTheOthersDoNotShare: the masks before differ in size");
  options.Check();
  std::vector<int> removed(n, 0);
  const int with_mask = CountMasks(rig, *masks);
  if (with_mask < 3) return removed;
  std::vector<Image> carving;
  VisualHullOptions hull_options;
  const std::vector<Image> hulls = ToleratedHulls(rig, *masks, with_mask, options, &carving, &hull_options, nullptr);
  for (std::size_t c = 0; c < n; ++c) {
    if (!refined[c] || (*masks)[c].empty() || cv::countNonZero(AsCvMat(hulls[c])) == 0) continue;
    const cv::Mat near = NearHull(AsCvMat(hulls[c]), options);
    std::vector<std::uint8_t>& mask = (*masks)[c].data;
    for (std::size_t i = 0; i < mask.size(); ++i)
      if (mask[i] && !near.data[i] && !before[c].data[i]) mask[i] = 0, ++removed[c];
  }
  return removed;
}

namespace {

// Vertical segments (from, to) drawn into `camera`'s view (1-channel 0/255), each a voxel wide.
Image DrawVerticalSegments(const Camera& camera, double voxel_m,
                           const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& segments) {
  Image drawn(camera.width, camera.height, 1);
  cv::Mat canvas = AsCvMat(drawn);
  const double focal = 0.5 * (camera.K(0, 0) + camera.K(1, 1));
  for (const auto& [from, to] : segments) {
    Eigen::Vector2d a, b;
    if (!camera.ProjectChecked(from, &a) || !camera.ProjectChecked(to, &b)) continue;
    const double depth = std::min(camera.PointInCamera(from).z(), camera.PointInCamera(to).z());
    const int width = std::max(1, static_cast<int>(std::lround(focal * voxel_m / depth)));
    cv::line(canvas, cv::Point(static_cast<int>(std::lround(a.x())), static_cast<int>(std::lround(a.y()))),
             cv::Point(static_cast<int>(std::lround(b.x())), static_cast<int>(std::lround(b.y()))), cv::Scalar(255),
             width);
  }
  return drawn;
}

}  // namespace

Image ProjectColumnsToFloor(const Camera& camera, const HullUnderside& underside) {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> segments;
  for (const Eigen::Vector3d& top : underside.lowest)
    if (top.z() > 0) segments.emplace_back(top, Eigen::Vector3d(top.x(), top.y(), 0.0));
  return DrawVerticalSegments(camera, underside.voxel_m, segments);
}

Image ProjectColumnsAboveTop(const Camera& camera, const HullUnderside& hull, double near_top_m, double height_m) {
  double top = -1e30;
  for (const Eigen::Vector3d& p : hull.highest) top = std::max(top, p.z());
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> segments;
  for (const Eigen::Vector3d& p : hull.highest)
    if (p.z() >= top - near_top_m) segments.emplace_back(p, p + Eigen::Vector3d(0, 0, height_m));
  return DrawVerticalSegments(camera, hull.voxel_m, segments);
}

std::vector<Image> LooseHullsOfTheOthers(const Rig& rig, const std::vector<Image>& masks, const MultiViewOptions& options) {
  options.Check();
  const int n = rig.size();
  if (static_cast<int>(masks.size()) != n) throw UsageError("LooseHullsOfTheOthers: one mask (or an empty image) per camera");
  const int with_mask = CountMasks(rig, masks);
  if (with_mask < 3) return std::vector<Image>(n);
  MultiViewOptions loose = options;
  loose.tolerated_rejections = std::min(4, (with_mask - 1) / 2);
  std::vector<Image> carving;
  VisualHullOptions hull_options;
  std::vector<Image> hulls = ToleratedHulls(rig, masks, with_mask, loose, &carving, &hull_options, nullptr);
  for (int c = 0; c < n; ++c)
    if (masks[c].empty()) hulls[c] = Image();
  return hulls;
}

int ClaimHighlightsInsideHull(Image* mask, const Image& frame, const BackgroundModel& model, const Image& hull,
                              const MultiViewOptions& options) {
  if (frame.width != mask->width || frame.height != mask->height || hull.width != mask->width ||
      hull.height != mask->height || model.width() != mask->width || model.height() != mask->height)
    throw UsageError("ClaimHighlightsInsideHull: mask, frame, model and hull must have one size");
  if (frame.channels != 3 || frame.type != PixelType::kUInt8)
    throw UsageError("ClaimHighlightsInsideHull: the frame must be 8-bit RGB");
  // Only the hull's box (with room for the closing) is worked on.
  const int deep = ScaledRadius(options.claim_margin, mask->width);
  const cv::Rect box = cv::boundingRect(AsCvMat(hull));
  if (box.empty()) return 0;
  const cv::Rect roi =
      (box + cv::Size(2 * deep, 2 * deep) - cv::Point(deep, deep)) & cv::Rect(0, 0, mask->width, mask->height);
  cv::Mat inside = AsCvMat(hull)(roi).clone();
  if (deep > 0) {
    // Closed first: the projected voxels leave pinholes that erosion would widen.
    cv::morphologyEx(inside, inside, cv::MORPH_CLOSE, Disk(deep), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
                     cv::Scalar(0));
    cv::erode(inside, inside, Disk(deep));
  }
  int added = 0;
  for (int y = 0; y < roi.height; ++y) {
    const std::uint8_t* within = inside.ptr<std::uint8_t>(y);
    std::uint8_t* out = &mask->at<std::uint8_t>(roi.x, roi.y + y);
    for (int x = 0; x < roi.width; ++x)
      if (within[x] != 0 && out[x] == 0 && model.ClassOf(frame, roi.x + x, roi.y + y) == PixelClass::kHighlight) {
        out[x] = 255;
        ++added;
      }
  }
  return added;
}

MaskTrust SummarizeMaskTrust(const Rig& rig, const std::vector<CameraFrameConfidence>& confidences,
                             double min_confidence, double max_hull_volume_m3) {
  const int n = rig.size();
  MaskTrust trust;
  std::vector<double> sum(n, 0.0);
  std::vector<int> count(n, 0);
  double total = 0;
  std::set<int> oversized;
  trust.checked = confidences;
  for (const CameraFrameConfidence& entry : confidences) {
    const int camera = entry.camera;
    const double confidence = entry.confidence;
    if (camera < 0 || camera >= n) throw UsageError("SummarizeMaskTrust: camera index out of range");
    ++trust.camera_frames;
    trust.largest_hull_m3 = std::max(trust.largest_hull_m3, entry.hull_volume_m3);
    if (max_hull_volume_m3 > 0 && entry.hull_volume_m3 > max_hull_volume_m3) oversized.insert(entry.frame);
    trust.low_confidence += confidence < min_confidence;
    sum[camera] += confidence;
    ++count[camera];
    total += confidence;
  }
  trust.camera_confidence.assign(n, 1.0);
  std::string worst;
  double worst_value = 2;
  for (int c = 0; c < n; ++c) {
    if (count[c] == 0) continue;
    trust.camera_confidence[c] = sum[c] / count[c];
    if (trust.camera_confidence[c] < worst_value) {
      worst_value = trust.camera_confidence[c];
      worst = rig.cameras[c].name;
    }
  }
  trust.oversized_hull_frames = static_cast<int>(oversized.size());
  if (trust.camera_frames == 0) return trust;
  trust.mean_confidence = total / trust.camera_frames;
  if (trust.low_confidence * 10 > trust.camera_frames || worst_value < min_confidence) {
    char text[512];
    std::snprintf(text, sizeof text,
                  "the silhouettes cannot be trusted: %d of %d camera-frames have a multi-view confidence below %.2f "
                  "(mean %.2f; worst camera %s, %.2f); tracking would follow these masks: record a clean plate "
                  "(background/<cam>.png), or give checked masks with --masks",
                  trust.low_confidence, trust.camera_frames, min_confidence, trust.mean_confidence, worst.c_str(),
                  worst_value);
    trust.warning = text;
    if (trust.oversized_hull_frames > 0) {
      std::snprintf(text, sizeof text,
                    "; in %d frame(s) the masks carve a visual hull of up to %.2f m^3, more than one person's (%.2f): "
                    "several cameras hold the same background (floor, walls)",
                    trust.oversized_hull_frames, trust.largest_hull_m3, max_hull_volume_m3);
      trust.warning += text;
    }
  }
  return trust;
}

MaskTrust AssessMaskTrust(const Rig& rig, const std::vector<int>& frames,
                          const std::function<Image(int camera, int frame)>& read_mask, const MultiViewOptions& options) {
  options.Check();
  const int n = rig.size();
  std::vector<CameraFrameConfidence> confidences;
  for (int frame : frames) {
    std::vector<Image> masks(n);
    for (int c = 0; c < n; ++c) masks[c] = read_mask(c, frame);
    const std::vector<ViewConsistency> views = CheckMultiView(rig, &masks, {}, options);
    for (int c = 0; c < n; ++c)
      if (!masks[c].empty()) confidences.push_back({c, frame, views[c].confidence, views[c].hull_volume_m3});
  }
  return SummarizeMaskTrust(rig, confidences, options.min_confidence, options.max_hull_volume_m3);
}

}  // namespace confluent
