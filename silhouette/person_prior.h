#pragma once
// The person prior for cameras without a plate. A background learned from the video holds
// ghosts: where the actor stood in front of a wall poster for most of the video, the poster
// never shows free and the learned background there is a guess, so the poster becomes
// "foreground". BlazePose (silhouette/person_segmenter.h) says where the person is: its
// segmentation joined with its limbs (thick lines between the landmarks, which hold a limb
// that the segmentation loses now and then) is the person's region, and masks are kept within
// reach of it. The background model still draws the boundary, at full resolution.

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/image.h"
#include "silhouette/person_segmenter.h"

namespace confluent {

// Whether cameras without a plate use the person prior.
enum class PersonPriorUse {
  kOff,
  kAuto,  // when the model is installed (a warning otherwise)
  kOn,    // an error when the model is missing
};
// "off", "auto", "on". Throws UsageError listing the names.
PersonPriorUse ParsePersonPriorUse(const std::string& name);

struct PersonPriorOptions {
  PersonPriorUse use = PersonPriorUse::kAuto;
  // The region: segmentation probability above this (0..1) ...
  double min_probability = 0.2;
  // ... and lines between the landmarks of at least this visibility, this thick (a fraction of
  // the person's height, the larger side of the segmentation's box).
  double min_visibility = 0.5;
  double limb_width = 0.08;
  // Masks are kept within this distance of the region (a fraction of the person's height).
  double reach = 0.04;
  // Probability (0..1) above which a pixel is the person's core: where a mask holds it, the
  // graph cut keeps it (an arm the wall's colour, that the cut would give to the room).
  double core_probability = 0.9;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// Where the person may be in one image (1 channel, 0/255, the image's size), with the person's
// height in pixels; empty Images when the model found nobody.
struct PersonRegion {
  Image region;
  Image core;          // where the person surely is (within the region)
  Image within_reach;  // the region grown by PersonPriorOptions::reach
  double height_px = 0;
};
PersonRegion MakePersonRegion(const PersonSegmentation& person, const PersonPriorOptions& options);

// `mask` (0/255) without what lies outside `person.within_reach`, except what `also` holds (same
// size, or empty: the other cameras' strict hull, where they see the person: a head that the
// prior lost in one frame); unchanged when the region is empty (nobody found: the prior does not
// know).
Image KeepNearPerson(const Image& mask, const PersonRegion& person, const Image& also = Image());

// Person regions of a capture's camera-frames for several threads: up to `processes`
// segmenters (Node processes) started as needed, each used by one thread at a time. A region
// asked for with `keep` (the background's sampled frames) is kept, PNG-compressed, until it is
// asked for again (that frame's extraction), so that a frame is segmented once.
class CapturePersonPrior {
 public:
  // Starts one segmenter, so that a missing model throws InputError here (see PersonSegmenter).
  CapturePersonPrior(const PersonSegmenterOptions& segmenter, const PersonPriorOptions& options, int processes);
  ~CapturePersonPrior();
  CapturePersonPrior(const CapturePersonPrior&) = delete;
  CapturePersonPrior& operator=(const CapturePersonPrior&) = delete;

  // The region of camera `camera` at `frame`, whose image is `rgb` (8-bit RGB); `source`
  // names the image in errors.
  PersonRegion Region(int camera, int frame, const Image& rgb, const std::string& source, bool keep = false);

 private:
  std::unique_ptr<PersonSegmenter> Acquire();
  void Release(std::unique_ptr<PersonSegmenter> segmenter);
  void Forget();  // one started segmenter fewer (it failed)

  PersonSegmenterOptions segmenter_options_;
  PersonPriorOptions options_;
  int processes_;
  std::mutex mutex_;
  std::condition_variable released_;
  std::vector<std::unique_ptr<PersonSegmenter>> idle_;
  int started_ = 0;
  struct Kept {
    std::vector<unsigned char> png;
    double height_px = 0;
  };
  std::map<std::pair<int, int>, Kept> kept_;
};

}  // namespace confluent
