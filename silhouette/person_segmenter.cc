#include "silhouette/person_segmenter.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <vector>

#include "core/child_process.h"
#include "core/cv_interop.h"
#include "core/error.h"

namespace confluent {
namespace fs = std::filesystem;
namespace {

constexpr int kSide = 256;                   // the model's square input
constexpr int kModelLandmarks = 39;          // 33 body landmarks and 6 auxiliary ones
constexpr char kReady[] = "CPSEG001";        // segment.js writes this once the model is loaded
constexpr std::size_t kReplyBytes = kSide * kSide + (kModelLandmarks * 5 + 1) * sizeof(float);

double Sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

cv::Rect AsRect(const PersonCrop& crop) { return {crop.x, crop.y, crop.side, crop.side}; }

// The square `crop` of `image`, black where it reaches outside the image.
cv::Mat SquareCrop(const cv::Mat& image, const cv::Rect& crop) {
  cv::Mat square(crop.height, crop.width, image.type(), cv::Scalar::all(0));
  const cv::Rect inside = crop & cv::Rect(0, 0, image.cols, image.rows);
  if (!inside.empty()) image(inside).copyTo(square(inside - crop.tl()));
  return square;
}

// The largest part of `mask`, as a box; empty when the mask is.
cv::Rect LargestPartBox(const cv::Mat& mask) {
  cv::Mat labels, stats, centroids;
  const int parts = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  int best = 0;
  for (int i = 1; i < parts; ++i)
    if (best == 0 || stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA)) best = i;
  if (best == 0) return {};
  return {stats.at<int>(best, cv::CC_STAT_LEFT), stats.at<int>(best, cv::CC_STAT_TOP),
          stats.at<int>(best, cv::CC_STAT_WIDTH), stats.at<int>(best, cv::CC_STAT_HEIGHT)};
}

}  // namespace

void PersonSegmenterOptions::Check() const {
  const std::string owner = "PersonSegmenterOptions.";
  if (node.empty()) throw UsageError(owner + "node = '': must not be empty (the Node.js executable)");
  if (crop_margins.empty()) throw UsageError(owner + "crop_margins: must not be empty");
  for (double margin : crop_margins) RequireOption(margin >= 1.0 && margin <= 3.0, owner + "crop_margins", margin, "in [1, 3]");
  RequireOption(good_presence >= 0.0 && good_presence <= 1.0, owner + "good_presence", good_presence, "in [0, 1]");
  RequireOption(threshold > 0.0 && threshold < 1.0, owner + "threshold", threshold, "in (0, 1)");
  RequireOption(min_presence >= 0.0 && min_presence < 1.0, owner + "min_presence", min_presence, "in [0, 1)");
}

std::string DefaultPersonSegmenterScript() {
  const char* override_path = std::getenv("CONFLUENT_PERSON_SEGMENTER");
  if (override_path != nullptr && override_path[0] != '\0') return override_path;
  return CONFLUENT_PERSON_SEGMENTER_SCRIPT;
}

PersonSegmenter::PersonSegmenter(const PersonSegmenterOptions& options) : options_(options) {
  options_.Check();
  script_ = options_.script.empty() ? DefaultPersonSegmenterScript() : options_.script;
  const fs::path folder = fs::path(script_).parent_path();
  const std::string install = "; .ci/install-deps.sh (which ./dev build runs) installs it";
  if (!fs::is_regular_file(script_)) throw InputError(script_, "the person segmenter's script is missing" + install);
  if (!fs::is_regular_file(folder / "models" / "blazepose-full.bin") ||
      !fs::is_directory(folder / "node_modules" / "@tensorflow" / "tfjs-backend-wasm"))
    throw InputError((folder / "models").string(), "the person segmenter's model or TensorFlow.js is missing" + install);
  log_path_ = (fs::temp_directory_path() /
               (".confluent_person" + std::to_string(getpid()) + "_" +
                std::to_string(reinterpret_cast<std::uintptr_t>(this)) + ".log"))
                  .string();
  try {
    node_ = std::make_unique<ChildProcess>(std::vector<std::string>{options_.node, script_}, log_path_, true);
  } catch (const std::system_error& error) {
    throw InputError(script_, "cannot run '" + options_.node + "' (" + std::strerror(error.code().value()) +
                                  "); install Node.js (Debian's nodejs)");
  }
  char ready[sizeof(kReady) - 1] = {};
  if (!node_->Receive(ready, sizeof(ready)) || std::memcmp(ready, kReady, sizeof(ready)) != 0) {
    const int status = node_->Finish();
    const std::string tail = TailOfFile(log_path_, 3);
    throw InputError(script_, "the person segmenter did not start (exit status " + std::to_string(status) + ")" +
                                  (tail.empty() ? "" : ": " + tail));
  }
}

PersonSegmenter::~PersonSegmenter() {
  if (node_) node_->Finish();
  std::error_code ignored;
  if (!log_path_.empty()) fs::remove(log_path_, ignored);
}

bool PersonSegmentation::found() const {
  for (std::uint8_t value : mask.data)
    if (value != 0) return true;
  return false;
}

PersonSegmentation PersonSegmenter::SegmentCrop(const Image& rgb, const PersonCrop& crop, const std::string& source) {
  PersonSegmentation result = RunCrop(rgb, crop, source);
  DropIfUnsure(&result);
  return result;
}

void PersonSegmenter::DropIfUnsure(PersonSegmentation* result) const {
  if (result->presence >= options_.min_presence) return;
  std::fill(result->probability.data.begin(), result->probability.data.end(), 0);
  std::fill(result->mask.data.begin(), result->mask.data.end(), 0);
}

PersonSegmentation PersonSegmenter::RunCrop(const Image& rgb_image, const PersonCrop& person_crop,
                                            const std::string& source) {
  if (rgb_image.empty() || rgb_image.channels != 3 || rgb_image.type != PixelType::kUInt8)
    throw UsageError("PersonSegmenter: the image must be 8-bit RGB");
  if (person_crop.side <= 0) throw UsageError("PersonSegmenter: the crop must not be empty");
  const cv::Mat rgb = AsCvMat(rgb_image);
  const cv::Rect crop = AsRect(person_crop);
  cv::Mat input;
  cv::resize(SquareCrop(rgb, crop), input, cv::Size(kSide, kSide), 0, 0, cv::INTER_AREA);
  std::vector<std::uint8_t> reply(kReplyBytes);
  if (!node_ || !node_->Send(input.data, input.total() * input.elemSize()) || !node_->Receive(reply.data(), reply.size())) {
    const int status = node_ ? node_->Finish() : -1;
    const std::string tail = TailOfFile(log_path_, 3);
    throw InputError(source.empty() ? script_ : source,
                     "the person segmenter stopped (exit status " + std::to_string(status) + ")" +
                         (tail.empty() ? "" : ": " + tail));
  }
  PersonSegmentation result;
  result.crop = person_crop;
  const cv::Mat probability(kSide, kSide, CV_8UC1, reply.data());
  cv::Mat scaled;
  cv::resize(probability, scaled, crop.size(), 0, 0, cv::INTER_LINEAR);
  cv::Mat full(rgb.size(), CV_8UC1, cv::Scalar::all(0));
  const cv::Rect inside = crop & cv::Rect(0, 0, rgb.cols, rgb.rows);
  if (!inside.empty()) scaled(inside - crop.tl()).copyTo(full(inside));
  std::vector<float> numbers(kModelLandmarks * 5 + 1);
  std::memcpy(numbers.data(), reply.data() + kSide * kSide, numbers.size() * sizeof(float));
  result.presence = numbers.back();
  cv::Mat mask;
  cv::compare(full, options_.threshold * 255.0, mask, cv::CMP_GT);
  result.probability = ImageFromCvMat(full);
  result.mask = ImageFromCvMat(mask);
  const double scale = static_cast<double>(crop.width) / kSide;
  for (int i = 0; i < kPersonLandmarks; ++i) {
    const float* landmark = numbers.data() + 5 * i;
    result.landmarks[i] = Eigen::Vector3f(static_cast<float>(crop.x + landmark[0] * scale),
                                          static_cast<float>(crop.y + landmark[1] * scale),
                                          static_cast<float>(Sigmoid(landmark[3])));
  }
  return result;
}

PersonSegmentation PersonSegmenter::Segment(const Image& rgb, const std::string& source) {
  const int whole_side = std::max(rgb.width, rgb.height);
  // The box comes from the whole image's segmentation even when the model doubts the pose there
  // (a small person); the crops decide.
  PersonSegmentation whole =
      RunCrop(rgb, {(rgb.width - whole_side) / 2, (rgb.height - whole_side) / 2, whole_side}, source);
  const cv::Rect box = LargestPartBox(AsCvMat(whole.mask));
  DropIfUnsure(&whole);
  if (box.empty()) return whole;
  // The first crop the model is sure of; else the surest crop it found a person in; else the
  // whole image's answer.
  PersonSegmentation best;
  const cv::Point centre(box.x + box.width / 2, box.y + box.height / 2);
  for (double margin : options_.crop_margins) {
    const int side = static_cast<int>(std::ceil(margin * std::max(box.width, box.height)));
    PersonSegmentation candidate = SegmentCrop(rgb, {centre.x - side / 2, centre.y - side / 2, side}, source);
    if (candidate.presence >= options_.good_presence) return candidate;
    if (best.probability.empty() || candidate.presence > best.presence) best = std::move(candidate);
  }
  return best.found() ? best : whole;
}

}  // namespace confluent
