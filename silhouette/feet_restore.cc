#include "silhouette/feet_restore.h"

#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "silhouette/disk_morphology.h"
#include "silhouette/multiview.h"

namespace confluent {

void FeetRestoreOptions::Check() const {
  const std::string owner = "FeetRestoreOptions.";
  RequireOption(max_height_m >= 0 && max_height_m <= 1, owner + "max_height_m", max_height_m, "in [0, 1]");
  RequireOption(min_chroma_angle_deg >= 0 && min_chroma_angle_deg < 90, owner + "min_chroma_angle_deg",
                min_chroma_angle_deg, "in [0, 90)");
  RequireOption(reach >= 0 && reach <= 100, owner + "reach", reach, "in [0, 100]");
}

int RestoreFeetBelowHull(Image* mask, const Image& frame, const Camera& camera, const HullUnderside& underside,
                         const BackgroundModel& model, const FeetRestoreOptions& options) {
  options.Check();
  if (!options.enabled) return 0;
  if (frame.width != mask->width || frame.height != mask->height || model.width() != mask->width ||
      model.height() != mask->height || camera.width != mask->width || camera.height != mask->height)
    throw UsageError("RestoreFeetBelowHull: mask, frame, model and camera must have one size");
  if (frame.channels != 3 || frame.type != PixelType::kUInt8)
    throw UsageError("RestoreFeetBelowHull: the frame must be 8-bit RGB");
  HullUnderside low;
  low.voxel_m = underside.voxel_m;
  for (const Eigen::Vector3d& voxel : underside.lowest)
    if (voxel.z() <= options.max_height_m) low.lowest.push_back(voxel);
  if (low.lowest.empty()) return 0;
  const cv::Mat columns =
      DilateByDisk(AsCvMat(ProjectColumnsToFloor(camera, low)), ScaledRadius(options.reach, mask->width));
  const cv::Rect box = cv::boundingRect(columns);  // the feet's few pixels, not the whole frame
  const double min_cos = std::cos(options.min_chroma_angle_deg * M_PI / 180.0);
  int added = 0;
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x) {
      std::uint8_t& out = mask->at<std::uint8_t>(x, y);
      if (out != 0 || columns.at<std::uint8_t>(y, x) == 0) continue;
      if (model.ClassOf(frame, x, y) != PixelClass::kForeground) continue;
      const std::uint8_t* colour = &frame.at<std::uint8_t>(x, y);
      const Eigen::Vector3f mean = model.MeanAt(x, y);
      double dot = 0, colour2 = 0, mean2 = 0;
      for (int k = 0; k < 3; ++k) {
        dot += colour[k] * static_cast<double>(mean[k]);
        colour2 += colour[k] * static_cast<double>(colour[k]);
        mean2 += static_cast<double>(mean[k]) * mean[k];
      }
      if (dot >= min_cos * std::sqrt(colour2 * mean2)) continue;  // the floor's colour, darker or lighter
      out = 255;
      ++added;
    }
  return added;
}

}  // namespace confluent
