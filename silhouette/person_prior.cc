#include "silhouette/person_prior.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "silhouette/disk_morphology.h"

namespace confluent {
namespace {

// BlazePose's bones: head (nose to ears), shoulders and hips, arms to the fingers, legs to the toes.
constexpr int kBones[][2] = {{0, 7},   {0, 8},   {7, 8},   {11, 12}, {11, 23}, {12, 24}, {23, 24}, {11, 13},
                             {13, 15}, {15, 17}, {15, 19}, {15, 21}, {12, 14}, {14, 16}, {16, 18}, {16, 20},
                             {16, 22}, {23, 25}, {25, 27}, {27, 29}, {27, 31}, {29, 31}, {24, 26}, {26, 28},
                             {28, 30}, {28, 32}, {30, 32}, {0, 11},  {0, 12}};

}  // namespace

PersonPriorUse ParsePersonPriorUse(const std::string& name) {
  if (name == "off") return PersonPriorUse::kOff;
  if (name == "auto") return PersonPriorUse::kAuto;
  if (name == "on") return PersonPriorUse::kOn;
  throw UsageError("--person-prior: expected auto, on or off, got '" + name + "'");
}

void PersonPriorOptions::Check() const {
  const std::string owner = "PersonPriorOptions.";
  RequireOption(min_probability > 0 && min_probability < 1, owner + "min_probability", min_probability, "in (0, 1)");
  RequireOption(min_visibility >= 0 && min_visibility <= 1, owner + "min_visibility", min_visibility, "in [0, 1]");
  RequireOption(limb_width >= 0 && limb_width <= 0.5, owner + "limb_width", limb_width, "in [0, 0.5]");
  RequireOption(reach >= 0 && reach <= 1, owner + "reach", reach, "in [0, 1]");
  RequireOption(core_probability > 0 && core_probability <= 1, owner + "core_probability", core_probability,
                "in (0, 1]");
}

PersonRegion MakePersonRegion(const PersonSegmentation& person, const PersonPriorOptions& options) {
  PersonRegion result;
  if (!person.found()) return result;
  cv::Mat region;
  cv::compare(AsCvMat(person.probability), options.min_probability * 255.0, region, cv::CMP_GT);
  const cv::Rect box = cv::boundingRect(region);
  result.height_px = std::max(box.width, box.height);
  const int thickness = std::max(1, static_cast<int>(std::lround(options.limb_width * result.height_px)));
  for (const auto& bone : kBones) {
    const Eigen::Vector3f& a = person.landmarks[bone[0]];
    const Eigen::Vector3f& b = person.landmarks[bone[1]];
    if (a.z() < options.min_visibility || b.z() < options.min_visibility) continue;
    cv::line(region, cv::Point(std::lround(a.x()), std::lround(a.y())), cv::Point(std::lround(b.x()), std::lround(b.y())),
             cv::Scalar(255), thickness, cv::LINE_8);
  }
  result.region = ImageFromCvMat(region);
  cv::Mat core;
  cv::compare(AsCvMat(person.probability), options.core_probability * 255.0, core, cv::CMP_GT);
  result.core = ImageFromCvMat(core);
  result.within_reach =
      ImageFromCvMat(DilateByDisk(region, static_cast<int>(std::lround(options.reach * result.height_px))));
  return result;
}

Image KeepNearPerson(const Image& mask, const PersonRegion& person, const Image& also) {
  if (person.within_reach.empty()) return mask;
  if (person.within_reach.width != mask.width || person.within_reach.height != mask.height)
    throw UsageError("KeepNearPerson: the person's region and the mask differ in size");
  if (!also.empty() && (also.width != mask.width || also.height != mask.height))
    throw UsageError("KeepNearPerson: the mask and what else it may keep differ in size");
  cv::Mat near, kept;
  if (also.empty()) near = AsCvMat(person.within_reach);
  else cv::bitwise_or(AsCvMat(person.within_reach), AsCvMat(also), near);
  cv::bitwise_and(AsCvMat(mask), near, kept);
  return ImageFromCvMat(kept);
}

CapturePersonPrior::CapturePersonPrior(const PersonSegmenterOptions& segmenter, const PersonPriorOptions& options,
                                       int processes)
    : segmenter_options_(segmenter), options_(options), processes_(std::max(1, processes)) {
  options_.Check();
  idle_.push_back(std::make_unique<PersonSegmenter>(segmenter_options_));
  started_ = 1;
}

CapturePersonPrior::~CapturePersonPrior() = default;

std::unique_ptr<PersonSegmenter> CapturePersonPrior::Acquire() {
  std::unique_lock<std::mutex> lock(mutex_);
  released_.wait(lock, [&] { return !idle_.empty() || started_ < processes_; });
  if (!idle_.empty()) {
    std::unique_ptr<PersonSegmenter> segmenter = std::move(idle_.back());
    idle_.pop_back();
    return segmenter;
  }
  ++started_;
  lock.unlock();
  try {
    return std::make_unique<PersonSegmenter>(segmenter_options_);
  } catch (...) {
    Forget();
    throw;
  }
}

void CapturePersonPrior::Forget() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    --started_;
  }
  released_.notify_one();
}

void CapturePersonPrior::Release(std::unique_ptr<PersonSegmenter> segmenter) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    idle_.push_back(std::move(segmenter));
  }
  released_.notify_one();
}

PersonRegion CapturePersonPrior::Region(int camera, int frame, const Image& rgb, const std::string& source,
                                        bool keep) {
  const std::pair<int, int> key(camera, frame);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto found = kept_.find(key);
    if (found != kept_.end()) {
      PersonRegion result;
      result.height_px = found->second.height_px;
      if (!found->second.png.empty()) {  // 85 = within reach, 170 = the region too, 255 = the core too
        const cv::Mat levels = cv::imdecode(found->second.png, cv::IMREAD_GRAYSCALE);
        result.within_reach = ImageFromCvMat(levels > 0);
        result.region = ImageFromCvMat(levels >= 170);
        result.core = ImageFromCvMat(levels == 255);
      }
      kept_.erase(found);
      return result;
    }
  }
  std::unique_ptr<PersonSegmenter> segmenter = Acquire();
  PersonSegmentation person;
  try {
    person = segmenter->Segment(rgb, source);
  } catch (...) {
    Forget();  // a segmenter that failed may be dead: it is not put back, another may start
    throw;
  }
  Release(std::move(segmenter));
  PersonRegion result = MakePersonRegion(person, options_);
  if (!keep) return result;
  Kept kept;
  kept.height_px = result.height_px;
  if (!result.region.empty()) {
    cv::Mat levels = AsCvMat(result.within_reach) / 3;
    levels.setTo(170, AsCvMat(result.region));
    levels.setTo(255, AsCvMat(result.core));
    cv::imencode(".png", levels, kept.png);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  kept_[key] = std::move(kept);
  return result;
}

}  // namespace confluent
