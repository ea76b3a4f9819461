#pragma once
// The tracker's landmark evidence (Tracker::UseLandmarks): each tracking camera's image of a
// frame through BlazePose (silhouette/person_segmenter.h), the landmarks triangulated into joints
// (tracking/landmark_joints.h). The segmenter starts on the first request; without Node.js or
// the model there are no landmarks, and a note says why.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "calib/capture.h"
#include "tracking/landmark_joints.h"

namespace confluent {

class PersonSegmenter;

class FrameLandmarks {
 public:
  // `use[c]`: camera c's images are looked at (the tracking cameras).
  FrameLandmarks(const Capture& capture, std::vector<bool> use);
  ~FrameLandmarks();
  FrameLandmarks(const FrameLandmarks&) = delete;
  FrameLandmarks& operator=(const FrameLandmarks&) = delete;

  // The joints of `frame` (each frame's images are looked at once: the tracker's look-ahead over
  // the first frames asks for the same frames again); null when the segmenter cannot start.
  std::shared_ptr<const LandmarkJoints> Joints(int frame);
  // One line per frame asked ("frame 0: landmarks placed 12 of 14 joints ..."), or why none.
  const std::vector<std::string>& notes() const { return notes_; }

 private:
  const Capture& capture_;
  std::vector<bool> use_;
  std::unique_ptr<PersonSegmenter> segmenter_;
  bool unavailable_ = false;
  std::vector<std::string> notes_;
  std::map<int, std::shared_ptr<const LandmarkJoints>> found_;
};

// "placed 12 of 14 joints (rms 3.1 px, 6-8 cameras agreeing)": for a run's notes.
std::string DescribeLandmarkJoints(const LandmarkJoints& joints);

}  // namespace confluent
