#include "calib/capture.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "calib/easymocap_io.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/image_io.h"
#include "core/video.h"

namespace confluent {
namespace fs = std::filesystem;

struct Capture::VideoCache {
  std::mutex mutex;
  std::map<int, VideoReader> readers;
};

Capture::Capture() : videos_(std::make_unique<VideoCache>()) {}
Capture::Capture(Capture&&) noexcept = default;
Capture& Capture::operator=(Capture&&) noexcept = default;
Capture::~Capture() = default;

namespace {

bool HasExtension(const fs::path& path, std::initializer_list<const char*> extensions) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
  for (const char* candidate : extensions)
    if (extension == candidate) return true;
  return false;
}

// Frame number of a 6-digit file name such as "000012.png", or -1.
int FrameNumber(const fs::path& path) {
  const std::string stem = path.stem().string();
  if (stem.size() != 6 || !std::all_of(stem.begin(), stem.end(), ::isdigit)) return -1;
  return std::stoi(stem);
}

std::vector<std::string> SubfolderNames(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.is_directory()) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Frame files of one camera folder, indexed by frame number; throws on gaps.
std::vector<std::string> ListFrames(const fs::path& folder) {
  std::map<int, std::string> frames;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file() || !HasExtension(entry.path(), {".png", ".jpg", ".jpeg", ".exr", ".tif", ".tiff"}))
      continue;
    const int number = FrameNumber(entry.path());
    if (number < 0) continue;
    if (frames.count(number))
      throw InputError(folder.string(), "two files for frame " + std::to_string(number) + ": " +
                                            fs::path(frames[number]).filename().string() + " and " +
                                            entry.path().filename().string());
    frames[number] = entry.path().string();
  }
  std::vector<std::string> paths;
  for (const auto& [number, path] : frames) {
    if (number != static_cast<int>(paths.size()))
      throw InputError(folder.string(), "frame " + std::to_string(paths.size()) + " is missing (frames must be "
                                        "numbered 000000, 000001, ... without gaps)");
    paths.push_back(path);
  }
  return paths;
}

std::string FindWithExtension(const fs::path& stem_path, std::initializer_list<const char*> extensions) {
  for (const char* extension : extensions) {
    fs::path candidate = stem_path;
    candidate += extension;
    if (fs::exists(candidate)) return candidate.string();
  }
  return {};
}

void CheckSize(const std::string& path, int width, int height, const Camera& camera) {
  if (width != camera.width || height != camera.height) {
    std::ostringstream message;
    message << "image is " << width << "x" << height << " but the calibration of camera " << camera.name << " says "
            << camera.width << "x" << camera.height;
    throw InputError(path, message.str());
  }
}

// Checks an image's size against `camera`. A difference of up to `fit_padding_px` rows and
// columns is sensor or encoder padding at the bottom and right: the camera takes the image's
// size (K unchanged: the principal point stays where it is in pixels) and `warnings` says so.
void CheckSize(const std::string& path, int width, int height, Camera* camera, int fit_padding_px,
               std::vector<std::string>* warnings) {
  if ((width != camera->width || height != camera->height) && std::abs(width - camera->width) <= fit_padding_px &&
      std::abs(height - camera->height) <= fit_padding_px && width > 0 && height > 0) {
    std::ostringstream message;
    message << "camera " << camera->name << ": images are " << width << "x" << height << " (" << path
            << ") but the calibration says " << camera->width << "x" << camera->height
            << ": taken as sensor padding at the bottom and right, the principal point kept at (" << camera->K(0, 2)
            << ", " << camera->K(1, 2) << "); if the padding is at the top or left, correct K_" << camera->name
            << " in intri.yml";
    warnings->push_back(message.str());
    camera->width = width;
    camera->height = height;
  }
  CheckSize(path, width, height, *camera);
}

// Lists cameras whose frame counts differ: "cam0: 10, cam1: 9".
std::string CountsList(const Rig& rig, const std::vector<int>& counts) {
  std::ostringstream list;
  for (int i = 0; i < rig.size(); ++i) list << (i ? ", " : "") << rig.cameras[i].name << ": " << counts[i];
  return list.str();
}

}  // namespace

Capture Capture::Open(const std::string& root_path, const CaptureOptions& options) {
  const fs::path root(root_path);
  if (!fs::is_directory(root)) throw InputError(root_path, "capture folder does not exist");
  const fs::path intri = root / "intri.yml", extri = root / "extri.yml";
  for (const auto& file : {intri, extri})
    if (!fs::exists(file)) throw InputError(file.string(), "missing (a capture needs intri.yml and extri.yml)");

  Capture capture;
  capture.root_ = fs::absolute(root).lexically_normal().string();
  capture.rig_ = ReadEasyMocap(intri.string(), extri.string());
  const Rig& rig = capture.rig_;
  if (rig.size() == 0) throw InputError(intri.string(), "lists no cameras");

  const fs::path images = root / "images", videos = root / "videos";
  std::vector<int> counts(rig.size(), 0);
  if (fs::is_directory(images)) {
    capture.source_ = FrameSource::kImages;
    for (const auto& folder : SubfolderNames(images))
      if (rig.IndexOf(folder) < 0)
        throw InputError((images / folder).string(), "camera folder '" + folder + "' is not in " + intri.string());
    for (int c = 0; c < rig.size(); ++c) {
      const fs::path folder = images / rig.cameras[c].name;
      if (!fs::is_directory(folder))
        throw InputError(folder.string(), "missing: camera " + rig.cameras[c].name + " is calibrated but has no image folder");
      capture.frame_paths_.push_back(ListFrames(folder));
      counts[c] = static_cast<int>(capture.frame_paths_.back().size());
    }
  } else if (fs::is_directory(videos)) {
    capture.source_ = FrameSource::kVideos;
    for (int c = 0; c < rig.size(); ++c) {
      const std::string path = FindWithExtension(videos / rig.cameras[c].name, {".mp4", ".avi", ".mov", ".mkv"});
      if (path.empty())
        throw InputError((videos / rig.cameras[c].name).string() + ".mp4",
                         "missing: camera " + rig.cameras[c].name + " is calibrated but has no video");
      VideoReader reader(path);
      CheckSize(path, reader.width(), reader.height(), &capture.rig_.cameras[c], options.fit_padding_px,
                &capture.warnings_);
      counts[c] = reader.num_frames();
      if (c == 0 && reader.fps() > 0 && reader.fps() <= 1000) capture.frame_rate_ = reader.fps();
      capture.video_paths_.push_back(path);
    }
  } else {
    throw InputError(root_path, "has neither images/ nor videos/");
  }

  if (std::adjacent_find(counts.begin(), counts.end(), std::not_equal_to<>()) != counts.end())
    throw InputError((capture.source_ == FrameSource::kImages ? images : videos).string(),
                     "cameras have unequal frame counts (" + CountsList(rig, counts) + ")");
  capture.num_frames_ = counts[0];
  if (capture.num_frames_ == 0) throw InputError(root_path, "capture has no frames");

  if (capture.source_ == FrameSource::kImages) {
    for (int c = 0; c < rig.size(); ++c) {
      const auto& paths = capture.frame_paths_[c];
      for (std::size_t f = 0; f < paths.size(); ++f) {
        if (!options.check_every_image_header && f != 0 && f + 1 != paths.size()) continue;
        const ImageInfo info = ReadImageInfo(paths[f]);
        // Padding is fitted on a camera's first frame only: its other frames must all match it.
        CheckSize(paths[f], info.width, info.height, &capture.rig_.cameras[c], f == 0 ? options.fit_padding_px : 0,
                  &capture.warnings_);
      }
    }
  }

  if (options.decode_every_frame) {
    const std::size_t total = static_cast<std::size_t>(rig.size()) * capture.num_frames_;
    std::size_t done = 0;
    for (int c = 0; c < rig.size(); ++c)
      for (int f = 0; f < capture.num_frames_; ++f) {
        capture.ReadFrame(c, f);
        ReportProgress(options.progress, "decode", ++done, total, rig.cameras[c].name);
      }
  }

  const fs::path masks = root / "masks";
  capture.has_masks_ = fs::is_directory(masks);
  for (int c = 0; c < rig.size() && capture.has_masks_; ++c)
    capture.has_masks_ = fs::is_directory(masks / rig.cameras[c].name);
  capture.scan_path_ = FindWithExtension(root / "scan", {".ply", ".obj"});
  if (fs::exists(root / "correspondences.json")) capture.correspondences_path_ = (root / "correspondences.json").string();
  return capture;
}

std::string Capture::FramePath(int camera, int frame) const {
  if (source_ == FrameSource::kVideos) return video_paths_.at(camera);
  return frame_paths_.at(camera).at(frame);
}

Image Capture::ReadFrame(int camera, int frame) const {
  if (frame < 0 || frame >= num_frames_)
    throw InputError(root_, "frame " + std::to_string(frame) + " out of range (capture has " +
                                std::to_string(num_frames_) + ")");
  if (source_ == FrameSource::kImages) return ToRgb8(ReadImage(FramePath(camera, frame)));
  std::lock_guard<std::mutex> lock(videos_->mutex);
  auto it = videos_->readers.find(camera);
  if (it == videos_->readers.end()) it = videos_->readers.emplace(camera, VideoReader(video_paths_.at(camera))).first;
  return it->second.ReadFrame(frame);
}

std::vector<Image> Capture::ReadFrames(const std::vector<int>& cameras, int frame, int threads) const {
  std::vector<Image> images(cameras.size());
  ParallelFor(static_cast<int>(cameras.size()), threads, [&](int i) { images[i] = ReadFrame(cameras[i], frame); });
  return images;
}

std::string Capture::MaskPath(int camera, int frame) const {
  char name[16];
  std::snprintf(name, sizeof name, "%06d.png", frame);
  return (fs::path(root_) / "masks" / rig_.cameras.at(camera).name / name).string();
}

Image Capture::ReadMask(int camera, int frame) const {
  const std::string path = MaskPath(camera, frame);
  Image mask = ReadMaskFile(path);
  CheckSize(path, mask.width, mask.height, rig_.cameras[camera]);
  return mask;
}

Image ReadMaskFile(const std::string& path) {
  Image read = ReadImage(path);
  // The first channel decides; 8-bit files are read as they are, deeper ones through ToRgb8.
  if (read.type != PixelType::kUInt8) read = ToRgb8(read);
  Image mask(read.width, read.height, 1);
  const std::size_t stride = read.channels;
  for (std::size_t i = 0; i < mask.data.size(); ++i) mask.data[i] = read.data[stride * i] >= 128 ? 255 : 0;
  return mask;
}

std::string Capture::BackgroundPath(int camera) const {
  return FindWithExtension(fs::path(root_) / "background" / rig_.cameras.at(camera).name, {".png", ".jpg", ".jpeg"});
}

const Image& AsRgb8(const Image& image, Image* storage) {
  if (image.type == PixelType::kUInt8 && image.channels == 3) return image;
  *storage = ToRgb8(image);
  return *storage;
}

Image ToRgb8(const Image& image) {
  if (image.type == PixelType::kUInt8 && image.channels == 3) return image;
  Image rgb(image.width, image.height, 3);
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) {
      const int source_channel = image.channels >= 3 ? c : 0;
      const std::size_t i = p * image.channels + source_channel;
      double value = 0;
      switch (image.type) {
        case PixelType::kUInt8: value = image.data[i]; break;
        case PixelType::kUInt16: value = image.ptr<std::uint16_t>()[i] / 257.0; break;
        case PixelType::kFloat32: value = image.ptr<float>()[i] * 255.0; break;
      }
      rgb.data[p * 3 + c] = static_cast<std::uint8_t>(std::clamp(value + 0.5, 0.0, 255.0));
    }
  }
  return rgb;
}

}  // namespace confluent
