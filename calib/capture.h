#pragma once
// The recorded camera folder (docs/ARCHITECTURE.md section 3): calibration, frames, plates, masks.

#include <memory>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/progress.h"

namespace confluent {

// Options for opening a capture folder.
struct CaptureOptions {
  // Read the header of every image (size check, readable format). Off: first and last only.
  bool check_every_image_header = true;
  // Fully decode every frame of every camera (slow; finds truncated or corrupt images).
  bool decode_every_frame = false;
  // Called once per decoded camera-frame when decode_every_frame is set.
  ProgressCallback progress;
  // Images up to this many rows or columns smaller or larger than the calibration says are
  // taken as sensor or encoder padding at the bottom and right (a Qualisys file giving the
  // sensor's 1088 rows for videos of 1080): the camera takes the images' size, its principal
  // point is kept, and warnings() says so. 0: any difference is an error.
  int fit_padding_px = 16;
};

enum class FrameSource { kImages, kVideos };

// An opened, validated capture folder. Holds open video decoders, so it is a class.
class Capture {
 public:
  // Opens and validates `root`: intri.yml/extri.yml readable and consistent; camera names in
  // the calibration and images/ (or videos/) agree; every camera has the same frame count with
  // no gaps; image sizes match the calibration (up to options.fit_padding_px of padding,
  // fitted with a warning); videos decode. Throws InputError naming the
  // file or folder and the problem (unequal counts list every camera and its count).
  static Capture Open(const std::string& root, const CaptureOptions& options = {});

  Capture(Capture&&) noexcept;
  Capture& operator=(Capture&&) noexcept;
  ~Capture();

  const std::string& root() const { return root_; }
  const Rig& rig() const { return rig_; }
  int num_cameras() const { return rig_.size(); }
  int num_frames() const { return num_frames_; }
  FrameSource source() const { return source_; }
  // Frames per second as the first camera's video file states it; 0 for images/ (unknown).
  double frame_rate() const { return frame_rate_; }

  // Path of frame `frame` of camera `camera` (images/ layout; for videos the video path).
  std::string FramePath(int camera, int frame) const;
  // Frame as 8-bit RGB (grey and RGBA images are converted). Throws InputError naming the file.
  Image ReadFrame(int camera, int frame) const;
  // ReadFrame of each of `cameras` at `frame`, decoded on up to `threads` threads, in order.
  std::vector<Image> ReadFrames(const std::vector<int>& cameras, int frame, int threads) const;

  // Precomputed masks (masks/<cam>/<frame>.png), present for every camera?
  bool has_masks() const { return has_masks_; }
  std::string MaskPath(int camera, int frame) const;
  // Mask as 1-channel 8-bit, 0 or 255 (thresholded at 128). Throws InputError naming the file.
  Image ReadMask(int camera, int frame) const;

  // What Open adjusted (sensor padding fitted), one line per camera, to show the user.
  const std::vector<std::string>& warnings() const { return warnings_; }

  // Clean plate background/<cam>.png|jpg, or "" when absent.
  std::string BackgroundPath(int camera) const;
  // Optional scan.ply|obj and correspondences.json, or "" when absent.
  const std::string& scan_path() const { return scan_path_; }
  const std::string& correspondences_path() const { return correspondences_path_; }

 private:
  Capture();
  struct VideoCache;
  std::string root_;
  Rig rig_;
  int num_frames_ = 0;
  double frame_rate_ = 0.0;
  FrameSource source_ = FrameSource::kImages;
  std::vector<std::vector<std::string>> frame_paths_;  // [camera][frame], images only
  std::vector<std::string> video_paths_;               // [camera], videos only
  bool has_masks_ = false;
  std::string scan_path_;
  std::string correspondences_path_;
  std::vector<std::string> warnings_;
  std::unique_ptr<VideoCache> videos_;
};

// Reads a mask file as 1-channel 8-bit 0/255 (first channel thresholded at half range).
// Throws InputError naming the file.
Image ReadMaskFile(const std::string& path);

// Converts any 1-4 channel 8/16-bit/float image to 8-bit RGB.
Image ToRgb8(const Image& image);
// `image` itself when it is 8-bit RGB already, else its ToRgb8 conversion kept in `storage`
// (the common case costs no full-frame copy).
const Image& AsRgb8(const Image& image, Image* storage);

}  // namespace confluent
