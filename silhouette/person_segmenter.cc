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
#include "core/error.h"

namespace confluent {
namespace fs = std::filesystem;
namespace {

constexpr int kSide = 256;                   // the model's square input
constexpr int kModelLandmarks = 39;          // 33 body landmarks and 6 auxiliary ones
constexpr char kReady[] = "CPSEG001";        // segment.js writes this once the model is loaded
constexpr std::size_t kReplyBytes = kSide * kSide + (kModelLandmarks * 5 + 1) * sizeof(float);

double Sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The square `crop` of `bgr`, black where it reaches outside the image.
cv::Mat SquareCrop(const cv::Mat& bgr, const cv::Rect& crop) {
  cv::Mat square(crop.height, crop.width, CV_8UC3, cv::Scalar::all(0));
  const cv::Rect inside = crop & cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (!inside.empty()) bgr(inside).copyTo(square(inside - crop.tl()));
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

PersonSegmentation PersonSegmenter::SegmentCrop(const cv::Mat& bgr, const cv::Rect& crop, const std::string& source) {
  return RunCrop(bgr, crop, source, false);
}

PersonSegmentation PersonSegmenter::RunCrop(const cv::Mat& bgr, const cv::Rect& crop, const std::string& source,
                                            bool keep_unsure) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw UsageError("PersonSegmenter: the image must be 8-bit BGR");
  if (crop.width <= 0 || crop.width != crop.height) throw UsageError("PersonSegmenter: the crop must be a square");
  cv::Mat input;
  cv::resize(SquareCrop(bgr, crop), input, cv::Size(kSide, kSide), 0, 0, cv::INTER_AREA);
  cv::cvtColor(input, input, cv::COLOR_BGR2RGB);
  std::vector<std::uint8_t> reply(kReplyBytes);
  if (!node_ || !node_->Send(input.data, input.total() * input.elemSize()) || !node_->Receive(reply.data(), reply.size())) {
    const int status = node_ ? node_->Finish() : -1;
    const std::string tail = TailOfFile(log_path_, 3);
    throw InputError(source.empty() ? script_ : source,
                     "the person segmenter stopped (exit status " + std::to_string(status) + ")" +
                         (tail.empty() ? "" : ": " + tail));
  }
  PersonSegmentation result;
  result.crop = crop;
  const cv::Mat probability(kSide, kSide, CV_8UC1, reply.data());
  cv::Mat scaled;
  cv::resize(probability, scaled, crop.size(), 0, 0, cv::INTER_LINEAR);
  result.probability = cv::Mat(bgr.size(), CV_8UC1, cv::Scalar::all(0));
  const cv::Rect inside = crop & cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (!inside.empty()) scaled(inside - crop.tl()).copyTo(result.probability(inside));
  std::vector<float> numbers(kModelLandmarks * 5 + 1);
  std::memcpy(numbers.data(), reply.data() + kSide * kSide, numbers.size() * sizeof(float));
  result.presence = numbers.back();
  if (result.presence < options_.min_presence && !keep_unsure) result.probability.setTo(0);
  cv::compare(result.probability, options_.threshold * 255.0, result.mask, cv::CMP_GT);
  const double scale = static_cast<double>(crop.width) / kSide;
  for (int i = 0; i < kPersonLandmarks; ++i) {
    const float* landmark = numbers.data() + 5 * i;
    result.landmarks[i] = Eigen::Vector3f(static_cast<float>(crop.x + landmark[0] * scale),
                                          static_cast<float>(crop.y + landmark[1] * scale),
                                          static_cast<float>(Sigmoid(landmark[3])));
  }
  return result;
}

PersonSegmentation PersonSegmenter::Segment(const cv::Mat& bgr, const std::string& source) {
  const int whole_side = std::max(bgr.cols, bgr.rows);
  // The box comes from the whole image's segmentation even when the model doubts the pose there
  // (a small person); the crops decide.
  PersonSegmentation whole =
      RunCrop(bgr, cv::Rect((bgr.cols - whole_side) / 2, (bgr.rows - whole_side) / 2, whole_side, whole_side), source,
              true);
  const cv::Rect box = LargestPartBox(whole.mask);
  if (whole.presence < options_.min_presence) {
    whole.probability.setTo(0);
    whole.mask.setTo(0);
  }
  if (box.empty()) return whole;
  // The first crop the model is sure of; else the surest crop it found a person in; else the
  // whole image's answer.
  PersonSegmentation best;
  const cv::Point centre(box.x + box.width / 2, box.y + box.height / 2);
  for (double margin : options_.crop_margins) {
    const int side = static_cast<int>(std::ceil(margin * std::max(box.width, box.height)));
    PersonSegmentation candidate =
        SegmentCrop(bgr, cv::Rect(centre.x - side / 2, centre.y - side / 2, side, side), source);
    if (candidate.presence >= options_.good_presence) return candidate;
    if (best.probability.empty() || candidate.presence > best.presence) best = std::move(candidate);
  }
  return best.found() ? best : whole;
}

}  // namespace confluent
