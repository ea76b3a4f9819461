#include "pipeline/frame_landmarks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include "core/error.h"
#include "silhouette/person_segmenter.h"

namespace confluent {

FrameLandmarks::FrameLandmarks(const Capture& capture, std::vector<bool> use) : capture_(capture), use_(std::move(use)) {}

FrameLandmarks::~FrameLandmarks() = default;

std::shared_ptr<const LandmarkJoints> FrameLandmarks::Joints(int frame) {
  if (unavailable_) return nullptr;
  if (const auto known = found_.find(frame); known != found_.end()) return known->second;
  if (!segmenter_) {
    try {
      segmenter_ = std::make_unique<PersonSegmenter>();
    } catch (const InputError& error) {
      unavailable_ = true;
      notes_.push_back(std::string("no landmarks (tracking from the silhouettes alone): ") + error.what());
      return nullptr;
    }
  }
  const Rig& rig = capture_.rig();
  std::vector<BodyLandmarks> found(rig.size());
  std::vector<const BodyLandmarks*> views(rig.size(), nullptr);
  for (int c = 0; c < rig.size(); ++c) {
    if (c >= static_cast<int>(use_.size()) || !use_[c]) continue;
    PersonSegmentation person;
    try {
      person = segmenter_->Segment(ToRgb8(capture_.ReadFrame(c, frame)), rig.cameras[c].name + " frame " + std::to_string(frame));
    } catch (const std::exception& error) {  // the segmenter died, or an image cannot be read
      unavailable_ = true;
      notes_.push_back("landmarks stopped at frame " + std::to_string(frame) + " (tracking goes on from the silhouettes): " +
                       error.what());
      return nullptr;
    }
    if (!person.found()) continue;
    for (int k = 0; k < kBodyLandmarks; ++k) found[c][k] = person.landmarks[k];
    views[c] = &found[c];
  }
  auto joints = std::make_shared<LandmarkJoints>(TriangulateLandmarkJoints(rig, views));
  notes_.push_back("frame " + std::to_string(frame) + ": landmarks " + DescribeLandmarkJoints(*joints));
  found_[frame] = joints;
  return joints;
}

std::string DescribeLandmarkJoints(const LandmarkJoints& joints) {
  int placed = 0, fewest = 0, most = 0;
  double sum = 0;
  for (std::size_t j = 0; j < joints.cameras.size(); ++j) {
    if (joints.cameras[j] <= 0) continue;
    fewest = placed ? std::min(fewest, joints.cameras[j]) : joints.cameras[j];
    most = std::max(most, joints.cameras[j]);
    sum += joints.rms_px[j] * joints.rms_px[j];
    ++placed;
  }
  char text[160];
  if (!placed) return "placed no joint (the cameras' landmarks do not agree)";
  std::snprintf(text, sizeof(text), "placed %d of %d joints (rms %.1f px, %d-%d cameras agreeing)", placed, kTriangulatedJoints,
                std::sqrt(sum / placed), fewest, most);
  return text;
}

}  // namespace confluent
