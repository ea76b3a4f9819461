#pragma once
// A learned person prior: MediaPipe's BlazePose model segments the person in an image and
// places 33 body landmarks, with no background model at all. It runs in Node.js
// (silhouette/person/segment.js, TensorFlow.js on WebAssembly; .ci/install-deps.sh installs it
// and fetches the model), one child process per segmenter, fed crops through a socket.
//
// The model sees a 256x256 crop that the person should fill. Segment() finds that crop in two
// passes: the whole image squared, whose person probability gives the person's box; then a
// square around that box (a few sizes, until the model is sure), whose answer is the result.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/image.h"

namespace confluent {

class ChildProcess;

struct PersonSegmenterOptions {
  std::string node = "node";  // the Node.js executable
  // segment.js; "" = $CONFLUENT_PERSON_SEGMENTER, else this source tree's silhouette/person/segment.js.
  std::string script;
  // Sides of the second pass's square over the larger side of the first pass's person box,
  // tried in turn until the model is sure of the pose (good_presence): its presence score swings
  // with the crop (a real frame: 1.00 at 1.1, 0.44 at 1.3, 0.82 at 1.6, 1.00 at 2.0).
  std::vector<double> crop_margins = {1.3, 1.15, 1.6};
  double good_presence = 0.9;
  // Probability (0..1) above which a pixel belongs to the person's box and mask.
  double threshold = 0.5;
  // Below this pose-presence score the crop holds nobody, and its segmentation (which the model
  // makes up regardless: 4-7 % of an empty studio room) is dropped.
  double min_presence = 0.5;
  // Throws UsageError naming the bad field.
  void Check() const;
};

constexpr int kPersonLandmarks = 33;

// A square of an image, in image pixels; it may reach outside the image.
struct PersonCrop {
  int x = 0;
  int y = 0;
  int side = 0;
};

struct PersonSegmentation {
  Image probability;  // 1 channel, 8 bits, the image's size: 255 = certainly the person (0 without a person)
  Image mask;         // 1 channel, 0/255: probability above the threshold
  // Body landmarks (BlazePose order: 0 nose ... 11/12 shoulders, 23/24 hips, 31/32 toes): image
  // pixels x, y and visibility in [0, 1]; all zero (unseen) until set. (`{}` alone would leave
  // them uninitialised: Eigen's default constructor does not zero.)
  std::array<Eigen::Vector3f, kPersonLandmarks> landmarks = [] {
    std::array<Eigen::Vector3f, kPersonLandmarks> unseen;
    unseen.fill(Eigen::Vector3f::Zero());
    return unseen;
  }();
  double presence = 0;  // the model's pose-presence score in [0, 1] for the final crop
  PersonCrop crop;      // the final crop
  bool found() const;   // the mask holds a pixel
};

class PersonSegmenter {
 public:
  // Starts the Node process and waits until the model is loaded. Throws InputError naming the
  // script or the model when they are missing (with what to run), or Node's own error.
  explicit PersonSegmenter(const PersonSegmenterOptions& options = {});
  ~PersonSegmenter();
  PersonSegmenter(const PersonSegmenter&) = delete;
  PersonSegmenter& operator=(const PersonSegmenter&) = delete;

  // The person in `rgb` (8-bit RGB). `source` names the image in errors.
  PersonSegmentation Segment(const Image& rgb, const std::string& source = {});
  // One pass on `crop`.
  PersonSegmentation SegmentCrop(const Image& rgb, const PersonCrop& crop, const std::string& source = {});

 private:
  // One pass, keeping the segmentation even where the model finds nobody.
  PersonSegmentation RunCrop(const Image& rgb, const PersonCrop& crop, const std::string& source);
  // Empties a result whose presence is below options_.min_presence.
  void DropIfUnsure(PersonSegmentation* result) const;

  PersonSegmenterOptions options_;
  std::string script_;
  std::string log_path_;
  std::unique_ptr<ChildProcess> node_;
};

// The script PersonSegmenter runs by default (see PersonSegmenterOptions::script).
std::string DefaultPersonSegmenterScript();

}  // namespace confluent
