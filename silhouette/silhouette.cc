#include "silhouette/silhouette.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/background_segm.hpp>
#include <thread>

#include "core/cv_interop.h"
#include "core/error.h"
#include "core/image_io.h"

namespace confluent {

SilhouetteMethod ParseSilhouetteMethod(const std::string& name) {
  if (name == "auto") return SilhouetteMethod::kAuto;
  if (name == "plate") return SilhouetteMethod::kPlate;
  if (name == "green") return SilhouetteMethod::kGreen;
  if (name == "learned") return SilhouetteMethod::kLearned;
  if (name == "mog2") return SilhouetteMethod::kMog2;
  if (name == "person") return SilhouetteMethod::kPerson;
  throw UsageError("--method: expected auto, plate, green, learned, mog2 or person, got '" + name + "'");
}

const char* SilhouetteMethodName(SilhouetteMethod method) {
  switch (method) {
    case SilhouetteMethod::kAuto: return "auto";
    case SilhouetteMethod::kPlate: return "plate";
    case SilhouetteMethod::kGreen: return "green";
    case SilhouetteMethod::kLearned: return "learned";
    case SilhouetteMethod::kMog2: return "mog2";
    case SilhouetteMethod::kPerson: return "person";
  }
  return "?";
}

void SilhouetteOptions::Check() const {
  background.Check();
  chroma.Check();
  cleanup.Check();
  const std::string owner = "SilhouetteOptions.";
  RequireOptions(empty_fraction >= 0 && empty_fraction < full_fraction && full_fraction <= 1, owner + "empty_fraction",
                 empty_fraction, owner + "full_fraction", full_fraction, "0 <= empty_fraction < full_fraction <= 1");
  RequireOption(area_jump_fraction > 0 && area_jump_fraction <= 1, owner + "area_jump_fraction", area_jump_fraction,
                "in (0, 1]");
  RequireOption(border_margin_px >= 0, owner + "border_margin_px", border_margin_px, ">= 0");
  RequireOption(threads >= 1 && threads <= 256, owner + "threads", threads, "in [1, 256]");
  RequireOption(max_parts >= 1, owner + "max_parts", max_parts, ">= 1");
  plate_free.Check();
  person.Check();
  person_prior.Check();
  grabcut.Check();
  feet.Check();
}

int SilhouetteSummary::num_flagged() const {
  int count = 0;
  for (const MaskSummary& mask : masks) count += mask.flagged() ? 1 : 0;
  return count;
}

MaskSummary SummarizeMask(const Image& mask, double previous_fraction, const SilhouetteOptions& options) {
  MaskSummary summary;
  const int w = mask.width, h = mask.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  const std::size_t count = pixels ? static_cast<std::size_t>(cv::countNonZero(AsCvMat(mask))) : 0;  // vectorised
  const std::uint8_t* p = mask.data.data();
  summary.foreground_fraction = pixels ? static_cast<double>(count) / pixels : 0.0;
  summary.empty = summary.foreground_fraction < options.empty_fraction || count == 0;
  summary.full = summary.foreground_fraction > options.full_fraction;
  const int m = std::min({options.border_margin_px, w / 2, h / 2});
  for (int y = 0; y < h && !summary.touches_border; ++y) {
    const std::uint8_t* row = p + static_cast<std::size_t>(y) * w;
    if (y < m || y >= h - m) {
      summary.touches_border = std::any_of(row, row + w, [](std::uint8_t v) { return v != 0; });
    } else {
      for (int x = 0; x < m && !summary.touches_border; ++x) summary.touches_border = row[x] || row[w - 1 - x];
    }
  }
  if (previous_fraction >= 0) {
    const double larger = std::max(previous_fraction, summary.foreground_fraction);
    summary.area_jump = larger > options.empty_fraction &&
                        std::abs(summary.foreground_fraction - previous_fraction) > options.area_jump_fraction * larger;
  }
  return summary;
}

struct SilhouetteExtractor::Mog2 {
  cv::Ptr<cv::BackgroundSubtractorMOG2> subtractor;
};

SilhouetteExtractor::SilhouetteExtractor(const std::string& camera_name, BackgroundModel learned,
                                         std::vector<std::string> warnings, const SilhouetteOptions& options)
    : options_(options), model_(std::move(learned)) {
  options.Check();
  if (model_.empty()) throw UsageError("SilhouetteExtractor: camera " + camera_name + " was given an empty background");
  info_.name = camera_name;
  info_.method = SilhouetteMethod::kLearned;
  info_.warnings = std::move(warnings);
  width_ = model_.width();
  height_ = model_.height();
  info_.noise_sigma = model_.noise_sigma();
  info_.threshold_scale = model_.threshold_scale();
}

SilhouetteExtractor::~SilhouetteExtractor() = default;
SilhouetteExtractor::SilhouetteExtractor(SilhouetteExtractor&&) noexcept = default;
SilhouetteExtractor& SilhouetteExtractor::operator=(SilhouetteExtractor&&) noexcept = default;

namespace {

std::string SizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

}  // namespace

// Up to `count` frame indices spread evenly over [0, num_frames).
std::vector<int> EvenFrameSample(int num_frames, int count) {
  std::vector<int> indices;
  if (num_frames <= count) {
    for (int k = 0; k < num_frames; ++k) indices.push_back(k);
    return indices;
  }
  for (int k = 0; k < count; ++k)
    indices.push_back(static_cast<int>(std::lround((k + 0.5) * num_frames / count - 0.5)));
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  return indices;
}

SilhouetteExtractor::SilhouetteExtractor(const std::string& camera_name, const std::string& plate_path,
                                         const FrameReader& read_frame, int num_frames, int first_frame,
                                         const SilhouetteOptions& options)
    : SilhouetteExtractor(camera_name,
                          plate_path.empty() ? std::vector<Image>{} : std::vector<Image>{ToRgb8(ReadImage(plate_path))},
                          plate_path, read_frame, num_frames, first_frame, options) {}

SilhouetteExtractor::SilhouetteExtractor(const std::string& camera_name, const std::vector<Image>& plates,
                                         const std::string& plate_source, const FrameReader& read_frame,
                                         int num_frames, int first_frame, const SilhouetteOptions& options)
    : options_(options) {
  options.Check();
  if (num_frames <= 0 || first_frame < 0 || first_frame >= num_frames)
    throw UsageError("silhouettes: first frame " + std::to_string(first_frame) + " is outside [0, " +
                     std::to_string(num_frames) + ")");
  info_.name = camera_name;
  const Image first = read_frame(first_frame);
  width_ = first.width;
  height_ = first.height;

  SilhouetteMethod method = options.method;
  const bool has_plate = !plates.empty();
  if (method == SilhouetteMethod::kAuto)
    method = has_plate ? SilhouetteMethod::kPlate
                       : LooksLikeGreenScreen(first, options.chroma) ? SilhouetteMethod::kGreen
                                                                     : SilhouetteMethod::kLearned;
  if (method == SilhouetteMethod::kLearned && !has_plate && options.method == SilhouetteMethod::kAuto)
    info_.warnings.push_back("no clean plate and no green screen: using a background learned from the video");
  if (method == SilhouetteMethod::kPlate && !has_plate) {
    info_.warnings.push_back("no clean plate (background/" + camera_name +
                             ".png): falling back to a background learned from the video");
    method = SilhouetteMethod::kLearned;
  }
  info_.method = method;

  if (has_plate && (method == SilhouetteMethod::kPlate || method == SilhouetteMethod::kMog2)) {
    for (const Image& plate : plates)
      if (plate.width != width_ || plate.height != height_)
        throw InputError(plate_source, "background plate is " + SizeText(plate.width, plate.height) +
                                           " but the frames of camera " + camera_name + " are " +
                                           SizeText(width_, height_));
    info_.plate_path = plate_source;
  }

  // Frames for refinement: the first ones of the range.
  auto frames_from = [&](int start, int count) {
    std::vector<Image> frames;
    for (int k = start; k < std::min(num_frames, start + count); ++k)
      frames.push_back(k == first_frame ? first : read_frame(k));
    return frames;
  };
  // Frames for learning: spread over the whole video, of the frames' size.
  auto learning_frames = [&]() {
    std::vector<Image> frames;
    for (int k : EvenFrameSample(num_frames, options.background.learned_frames)) {
      Image frame = k == first_frame ? first : read_frame(k);
      if (frame.width == width_ && frame.height == height_) frames.push_back(std::move(frame));
    }
    return frames;
  };

  switch (method) {
    case SilhouetteMethod::kPlate: {
      std::vector<Image> rgb_plates;
      for (const Image& plate : plates) rgb_plates.push_back(ToRgb8(plate));
      model_ = BackgroundModel::FromPlates(rgb_plates, options.background, plate_source);
      if (options.background.refine_frames > 0) {
        model_.Adapt(frames_from(first_frame, options.background.refine_frames));
      } else if (options.background.auto_thresholds) {
        model_.AutoThreshold({first});
      }
      break;
    }
    case SilhouetteMethod::kLearned: {
      std::vector<Image> frames = learning_frames();
      if (frames.size() < 3)
        throw InputError(camera_name, "cannot learn a background from " + std::to_string(frames.size()) +
                                          " frame(s); give a clean plate in background/" + camera_name + ".png");
      info_.warnings.push_back("background learned as the temporal median of " + std::to_string(frames.size()) +
                               " frames; parts of the actor that never move may be missed");
      model_ = BackgroundModel::FromFrames(frames, options.background, camera_name);
      if (options.background.auto_thresholds) {
        frames.resize(std::min<std::size_t>(frames.size(), 5));
        model_.AutoThreshold(frames);
      }
      break;
    }
    case SilhouetteMethod::kGreen:
      info_.greenness = ChooseGreenness(first, options.chroma);
      break;
    case SilhouetteMethod::kMog2: {
      mog2_ = std::make_unique<Mog2>();
      mog2_->subtractor = cv::createBackgroundSubtractorMOG2(500, 16.0, true);
      // OpenCV's subtractor works in BGR order, but only its distances matter: RGB is fine.
      if (has_plate) {
        cv::Mat ignored;
        for (int k = 0; k < std::max<int>(30, plates.size()); ++k) {
          const Image plate = ToRgb8(plates[k % plates.size()]);
          mog2_->subtractor->apply(AsCvMat(plate), ignored, k == 0 ? 1.0 : 1.0 / (k + 1));
        }
      } else {
        for (const Image& frame : learning_frames()) {
          cv::Mat ignored;
          mog2_->subtractor->apply(AsCvMat(frame), ignored, -1);
        }
        info_.warnings.push_back("MOG2 without a clean plate: primed with frames of the video");
      }
      break;
    }
    case SilhouetteMethod::kPerson:
      person_ = std::make_unique<PersonSegmenter>(options.person);
      break;
    case SilhouetteMethod::kAuto: break;  // resolved above
  }
  if (!model_.empty()) {
    info_.noise_sigma = model_.noise_sigma();
    info_.threshold_scale = model_.threshold_scale();
  }
}

Image SilhouetteExtractor::Extract(const Image& frame, int frame_index, MaskSummary* summary,
                                   const std::string& source) {
  Image converted;
  const Image& rgb = AsRgb8(frame, &converted);
  if (rgb.width != width_ || rgb.height != height_)
    throw InputError(source, "frame is " + SizeText(rgb.width, rgb.height) + " but camera " + info_.name +
                                 " was set up for " + SizeText(width_, height_));
  Image raw;
  switch (info_.method) {
    case SilhouetteMethod::kGreen: raw = ChromaKey(rgb, info_.greenness, options_.chroma); break;
    case SilhouetteMethod::kMog2: {
      cv::Mat foreground;
      mog2_->subtractor->apply(AsCvMat(rgb), foreground, -1);
      cv::threshold(foreground, foreground, 200, 255, cv::THRESH_BINARY);  // shadows (127) are background
      raw = ImageFromCvMat(foreground);
      break;
    }
    case SilhouetteMethod::kPerson: raw = person_->Segment(rgb, source.empty() ? info_.name : source).mask; break;
    default: raw = model_.Classify(rgb); break;
  }
  MaskCleanupStats stats;
  Image mask = CleanMask(raw, options_.cleanup, &stats);
  MaskSummary local = SummarizeMask(mask, previous_fraction_, options_);
  local.frame = frame_index;
  local.parts = stats.parts_kept;
  local.fragmented = stats.parts_kept > options_.max_parts;
  previous_fraction_ = local.foreground_fraction;
  if (summary != nullptr) *summary = local;
  return mask;
}

}  // namespace confluent
