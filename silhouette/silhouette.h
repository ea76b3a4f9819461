#pragma once
// Silhouette extraction for a camera or a whole capture: background model (clean plate,
// learned, or OpenCV MOG2) or green-screen key, then mask clean-up and per-frame checks.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "calib/capture.h"
#include "core/image.h"
#include "core/progress.h"
#include "silhouette/background_model.h"
#include "silhouette/chroma_key.h"
#include "silhouette/feet_restore.h"
#include "silhouette/grabcut_refine.h"
#include "silhouette/mask_cleanup.h"
#include "silhouette/multiview.h"
#include "silhouette/person_prior.h"
#include "silhouette/person_segmenter.h"
#include "silhouette/plate_free.h"

namespace confluent {

// How foreground is found.
enum class SilhouetteMethod {
  kAuto,     // the plate if there is one, else a green key if the frame looks green, else learned
  kPlate,    // clean plate + Horprasert classifier (falls back to learned, with a warning)
  kGreen,    // chroma key against a green screen
  kLearned,  // temporal median background learned from the video + Horprasert classifier
  kMog2,     // OpenCV's Gaussian-mixture background subtractor (Zivkovic 2004), fed the plate first
  kPerson,   // a learned person prior, no background at all (BlazePose, silhouette/person_segmenter.h)
};

// "auto", "plate", "green", "learned", "mog2", "person". Throws UsageError listing the names.
SilhouetteMethod ParseSilhouetteMethod(const std::string& name);
const char* SilhouetteMethodName(SilhouetteMethod method);

// Everything that controls silhouette extraction.
struct SilhouetteOptions {
  SilhouetteMethod method = SilhouetteMethod::kAuto;
  BackgroundModelOptions background;
  ChromaKeyOptions chroma;
  MaskCleanupOptions cleanup;
  // Summary flags: a mask is empty below this foreground fraction, full above the other.
  double empty_fraction = 1e-4;
  double full_fraction = 0.9;
  // An area change between consecutive frames of more than this fraction of the larger area
  // is a sudden jump.
  double area_jump_fraction = 0.35;
  // Mask pixels within this distance of the image edge make the actor "touch the border".
  int border_margin_px = 1;
  // A mask of more than this many kept parts is fragmented.
  int max_parts = 3;
  // Cameras without a plate (learned method) learn their backgrounds together, through the
  // other cameras' hulls (silhouette/plate_free.h); false: each its own temporal median.
  bool plate_free_multiview = true;
  PlateFreeOptions plate_free;
  PersonSegmenterOptions person;  // the person method, and the person prior's segmenter
  // Cameras without a plate (learned) keep their masks, and their backgrounds' samples of the
  // actor, within reach of where a person prior finds the person (silhouette/person_prior.h).
  PersonPriorOptions person_prior;
  // Every frame's masks are checked against the other cameras' hulls (a confidence per
  // camera-frame); the masks of cameras without a plate are also corrected by it.
  bool multiview_check = true;
  bool multiview_correct_learned = true;
  bool multiview_correct_plates = false;
  // Where the other cameras' hull says the actor is, a plate camera's "highlights" of the
  // background are the actor (ClaimHighlightsInsideHull).
  bool plate_claim_inside_hull = true;
  // Cameras kept out of both (empty, or one flag per camera): held-out cameras, whose images
  // must not shape the masks of the cameras that are evaluated against them. They keep their
  // own background (temporal median without a plate) and are not checked (confidence 1).
  std::vector<bool> multiview_exclude;
  // The corrected masks of cameras without a plate are then refined by a graph cut on colour
  // models of the actor and its surroundings (silhouette/grabcut_refine.h).
  bool grabcut_learned = true;
  GrabCutRefineOptions grabcut;
  // After it, dark feet that the graph cut took for the floor's shadow are put back from below
  // the other cameras' hull (silhouette/feet_restore.h); cameras without a plate only.
  FeetRestoreOptions feet;
  // Then the masks are checked against each other again, and what a camera's cut added beyond
  // the hull of the others' refined masks is removed (a poster in the shirt's colours beside the
  // body); what the mask held before the cut stays.
  bool recheck_after_cut = true;
  // Worker threads for a capture (cameras are processed in parallel).
  int threads = 2;
  // Throws UsageError naming the bad field (also of the nested options).
  void Check() const;
};

// Checks of one camera's mask in one frame.
struct MaskSummary {
  int camera = 0;
  int frame = 0;
  double foreground_fraction = 0;  // of the image's pixels
  int parts = 0;                   // connected components kept
  bool empty = false;              // foreground_fraction < empty_fraction
  bool full = false;               // foreground_fraction > full_fraction
  bool touches_border = false;     // the actor reaches the image edge
  bool area_jump = false;          // area changed suddenly since the previous frame
  bool fragmented = false;         // more than max_parts parts
  // Multi-view check (silhouette/multiview.h); 1 when not checked.
  double hull_explained = 1;  // fraction of the mask near the other cameras' hull
  double hull_covered = 1;    // fraction of that hull the mask covers
  double hull_volume_m3 = 0;  // of the frame's hull of every camera's mask (0: not checked)
  // In [0, 1]: the hull consistency, lowered by a quarter for an area jump and for fragmentation.
  double confidence = 1;
  bool low_confidence = false;  // confidence < plate_free.multiview.min_confidence
  int corrected_pixels = 0;     // pixels the multi-view correction added or removed
  bool flagged() const { return empty || full || touches_border || area_jump || fragmented || low_confidence; }
};

// How one camera was processed.
struct CameraSilhouetteInfo {
  std::string name;
  SilhouetteMethod method = SilhouetteMethod::kAuto;  // the method actually used
  std::string plate_path;        // empty when no plate was used
  double noise_sigma = 0;        // estimated sensor noise, grey levels (background models)
  double threshold_scale = 1;    // automatic threshold factor (background models)
  double greenness = 0;          // chroma-key threshold (green)
  std::vector<std::string> warnings;
};

// The whole run: per camera, and per camera and frame.
struct SilhouetteSummary {
  std::vector<CameraSilhouetteInfo> cameras;
  std::vector<MaskSummary> masks;      // ordered by camera, then frame
  std::vector<std::string> warnings;   // all cameras' warnings, prefixed by the camera name
  MaskTrust trust;                     // the multi-view confidences summarised (its warning is in warnings too)
  int num_flagged() const;
};

// Extracts the silhouettes of one camera, frame after frame (keeps the model and the previous
// frame's area, hence a class). Frames are 8-bit RGB.
class SilhouetteExtractor {
 public:
  // Reads a frame of this camera by index; may throw InputError.
  using FrameReader = std::function<Image(int frame)>;

  // Prepares the camera: resolves the method, loads the plate (`plate_path`, "" when none),
  // learns or refines the background from frames obtained through `read_frame` (indices in
  // [0, num_frames)), and picks thresholds. `first_frame` is where processing will start (used
  // for refinement and detection). Throws InputError naming the plate when it cannot be read
  // or differs in size from the frames, UsageError for bad options.
  SilhouetteExtractor(const std::string& camera_name, const std::string& plate_path, const FrameReader& read_frame,
                      int num_frames, int first_frame, const SilhouetteOptions& options);
  // As above with the plate(s) given as images (several: per-pixel statistics over them, e.g.
  // frames of a background video); `plate_source` names them in errors and in info().
  SilhouetteExtractor(const std::string& camera_name, const std::vector<Image>& plates,
                      const std::string& plate_source, const FrameReader& read_frame, int num_frames,
                      int first_frame, const SilhouetteOptions& options);
  // A learned background prepared elsewhere (LearnBackgroundsWithoutPlates), with the warnings
  // for info(); frames must have the model's size.
  SilhouetteExtractor(const std::string& camera_name, BackgroundModel learned, std::vector<std::string> warnings,
                      const SilhouetteOptions& options);
  ~SilhouetteExtractor();
  SilhouetteExtractor(SilhouetteExtractor&&) noexcept;
  SilhouetteExtractor& operator=(SilhouetteExtractor&&) noexcept;

  // The cleaned mask (1 channel, 0/255) of `frame`, the frame with index `frame_index`, and
  // its checks. Throws InputError(`source`) if the frame's size differs from the model's.
  Image Extract(const Image& frame, int frame_index, MaskSummary* summary, const std::string& source = {});

  const CameraSilhouetteInfo& info() const { return info_; }
  // The background model (empty for the green key and MOG2).
  const BackgroundModel& model() const { return model_; }

 private:
  struct Mog2;
  SilhouetteOptions options_;
  CameraSilhouetteInfo info_;
  BackgroundModel model_;
  std::unique_ptr<Mog2> mog2_;
  std::unique_ptr<PersonSegmenter> person_;  // the person method's Node process
  int width_ = 0;
  int height_ = 0;
  double previous_fraction_ = -1;  // < 0 before the first frame
};

// Up to `count` frame indices spread evenly over [0, num_frames) (the frames a learned
// background is made from).
std::vector<int> EvenFrameSample(int num_frames, int count);

// Computes the summary flags of a cleaned mask; `previous_fraction` < 0 means no previous frame.
MaskSummary SummarizeMask(const Image& mask, double previous_fraction, const SilhouetteOptions& options);

// Receives each camera's frame and its mask; called from worker threads (must be thread-safe).
using MaskSink = std::function<void(int camera, int frame, const Image& image, const Image& mask,
                                    const MaskSummary& summary)>;

// Extracts silhouettes for frames [first_frame, end_frame) of every camera of `capture`, frame
// after frame with the cameras in parallel (options.threads), reporting progress per
// camera-frame ("silhouettes"). Cameras without a plate learn their backgrounds together
// (options.plate_free_multiview); each frame's masks are then checked, and corrected, against
// the other cameras' hulls before they reach the sink (options.multiview_*).
// Plates are the capture's background/<cam> images. Throws InputError naming the file for bad
// plates or frames, UsageError for a bad range or options.
// `resume_at` (empty, or one frame per camera in [first_frame, end_frame]) resumes a camera
// there: its earlier frames reach neither the sink nor the progress (they are still extracted
// from the earliest resumed frame on, for the multi-view check; MOG2 sees every frame). The
// extractors are prepared at frame 0 whatever the range (plate adaptation, method detection), so
// that a range gives the masks of a run over the whole capture (except MOG2, which learns from
// the frames it sees).
SilhouetteSummary ExtractSilhouettes(const Capture& capture, int first_frame, int end_frame,
                                     const SilhouetteOptions& options, const MaskSink& sink,
                                     const ProgressCallback& progress = {}, const std::vector<int>& resume_at = {});

}  // namespace confluent
