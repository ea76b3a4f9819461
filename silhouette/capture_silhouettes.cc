// ExtractSilhouettes (silhouette/silhouette.h): a whole capture, frame after frame, with the
// backgrounds of cameras without a plate learned together and every frame's masks checked
// against the other cameras' hulls.

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <memory>
#include <mutex>
#include <utility>

#include "core/cv_interop.h"
#include "core/error.h"
#include "core/parallel.h"
#include "silhouette/silhouette.h"

namespace confluent {
namespace {

// Replaces the temporal-median extractors of the cameras without a plate by backgrounds learned
// together (LearnBackgroundsWithoutPlates), when 3 or more cameras can give masks.
// With `prior`, the person's regions in the sampled frames guide the learning.
void LearnPlateFreeTogether(const Capture& capture, const SilhouetteOptions& options, CapturePersonPrior* prior,
                            const ProgressCallback& progress,
                            std::vector<std::unique_ptr<SilhouetteExtractor>>* extractors) {
  const int n = capture.num_cameras();
  std::vector<BackgroundModel> models(n);
  int learned = 0, usable = 0;
  auto excluded = [&](int c) { return !options.multiview_exclude.empty() && options.multiview_exclude[c]; };
  for (int c = 0; c < n; ++c) {
    if (excluded(c)) continue;
    const SilhouetteMethod method = (*extractors)[c]->info().method;
    learned += method == SilhouetteMethod::kLearned;
    usable += method == SilhouetteMethod::kLearned || method == SilhouetteMethod::kPlate;
    if (method == SilhouetteMethod::kPlate) models[c] = (*extractors)[c]->model();
  }
  if (learned == 0 || usable < 3) return;
  const std::vector<int> samples = EvenFrameSample(capture.num_frames(), options.background.learned_frames);
  if (samples.size() < 3) return;  // the extractors already refused or warned
  std::vector<std::vector<Image>> frames(n);
  ParallelFor(n, options.threads, [&](int c) {
    const SilhouetteMethod method = (*extractors)[c]->info().method;
    if (excluded(c) || (method != SilhouetteMethod::kLearned && method != SilhouetteMethod::kPlate)) return;
    for (int k : samples) frames[c].push_back(ToRgb8(capture.ReadFrame(c, k)));
  });
  std::vector<std::vector<PersonRegion>> people;
  if (prior != nullptr) {
    people.resize(n);
    std::mutex mutex;  // guards progress reports
    std::size_t done = 0, total = 0;
    for (int c = 0; c < n; ++c)
      if ((*extractors)[c]->info().method == SilhouetteMethod::kLearned) total += frames[c].size();
    ParallelFor(n, options.threads, [&](int c) {
      if ((*extractors)[c]->info().method != SilhouetteMethod::kLearned) return;
      for (std::size_t k = 0; k < frames[c].size(); ++k) {
        people[c].push_back(
            prior->Region(c, samples[k], frames[c][k], capture.FramePath(c, samples[k]), true));
        std::lock_guard<std::mutex> lock(mutex);
        ReportProgress(progress, "person prior", ++done, total,
                       capture.rig().cameras[c].name + " frame " + std::to_string(samples[k]));
      }
    });
  }
  std::vector<std::string> notes;
  models = LearnBackgroundsWithoutPlates(capture.rig(), frames, models, options.background, options.cleanup,
                                         options.plate_free, &notes, options.threads,
                                         prior != nullptr ? &people : nullptr);
  for (int c = 0; c < n; ++c) {
    if (excluded(c) || (*extractors)[c]->info().method != SilhouetteMethod::kLearned) continue;
    std::vector<std::string> warnings;
    for (const std::string& warning : (*extractors)[c]->info().warnings)
      if (warning.rfind("background learned as the temporal median", 0) != 0) warnings.push_back(warning);
    const std::string prefix = capture.rig().cameras[c].name + ": ";
    for (const std::string& note : notes)
      if (note.rfind(prefix, 0) == 0) warnings.push_back(note.substr(prefix.size()));
    (*extractors)[c] = std::make_unique<SilhouetteExtractor>(capture.rig().cameras[c].name, std::move(models[c]),
                                                             std::move(warnings), options);
  }
}

// `a` and `b` (0/255 masks) both set; empty when `a` is.
Image Intersect(const Image& a, const Image& b) {
  if (a.empty()) return a;
  cv::Mat both;
  cv::bitwise_and(AsCvMat(a), AsCvMat(b), both);
  return ImageFromCvMat(both);
}

// Replaces `*mask` by `corrected` and returns how many pixels changed (reported as corrected).
int ReplaceMask(Image* mask, Image corrected) {
  int changed = 0;
  for (std::size_t i = 0; i < corrected.data.size(); ++i) changed += corrected.data[i] != mask->data[i];
  *mask = std::move(corrected);
  return changed;
}

}  // namespace

SilhouetteSummary ExtractSilhouettes(const Capture& capture, int first_frame, int end_frame,
                                     const SilhouetteOptions& options, const MaskSink& sink,
                                     const ProgressCallback& progress, const std::vector<int>& resume_at) {
  options.Check();
  if (first_frame < 0 || end_frame > capture.num_frames() || first_frame >= end_frame)
    throw UsageError("--frames " + std::to_string(first_frame) + ":" + std::to_string(end_frame) +
                     " is not a non-empty range within 0:" + std::to_string(capture.num_frames()));
  const int num_cameras = capture.num_cameras();
  const int num_frames = end_frame - first_frame;
  if (!resume_at.empty() && static_cast<int>(resume_at.size()) != num_cameras) std::abort();
  if (!options.multiview_exclude.empty() && static_cast<int>(options.multiview_exclude.size()) != num_cameras)
    throw UsageError("SilhouetteOptions.multiview_exclude: one flag per camera of the capture (" +
                     std::to_string(num_cameras) + "), got " + std::to_string(options.multiview_exclude.size()));
  auto excluded = [&](int c) { return !options.multiview_exclude.empty() && options.multiview_exclude[c]; };
  for (int frame : resume_at)
    if (frame < first_frame || frame > end_frame) std::abort();
  auto resume = [&](int c) { return resume_at.empty() ? first_frame : resume_at[c]; };
  SilhouetteSummary summary;
  summary.cameras.resize(num_cameras);
  summary.masks.resize(static_cast<std::size_t>(num_cameras) * num_frames);

  // Every extractor is prepared at the capture's first frame whatever the range, so that shards
  // (--frames A:B) write the masks of one run over the whole capture.
  std::vector<std::unique_ptr<SilhouetteExtractor>> extractors(num_cameras);
  ParallelFor(num_cameras, options.threads, [&](int c) {
    extractors[c] = std::make_unique<SilhouetteExtractor>(
        capture.rig().cameras[c].name, capture.BackgroundPath(c),
        [&capture, c](int frame) { return capture.ReadFrame(c, frame); }, capture.num_frames(), 0, options);
  });
  // The person prior of the cameras without a plate; in auto mode a missing model is a warning.
  std::vector<bool> use_prior(num_cameras, false);
  for (int c = 0; c < num_cameras; ++c) use_prior[c] = extractors[c]->info().method == SilhouetteMethod::kLearned;
  std::unique_ptr<CapturePersonPrior> prior;
  std::string prior_warning;
  if (options.person_prior.use != PersonPriorUse::kOff &&
      std::find(use_prior.begin(), use_prior.end(), true) != use_prior.end()) {
    try {
      prior = std::make_unique<CapturePersonPrior>(options.person, options.person_prior, options.threads);
    } catch (const InputError& error) {
      if (options.person_prior.use == PersonPriorUse::kOn) throw;
      prior_warning = std::string("no person prior for the cameras without a plate (") + error.what() +
                      "): their masks may keep parts of the room the actor stood in front of";
    }
  }
  if (options.plate_free_multiview) LearnPlateFreeTogether(capture, options, prior.get(), progress, &extractors);
  bool mog2 = false;
  std::vector<bool> correct(num_cameras, false);
  for (int c = 0; c < num_cameras; ++c) {
    summary.cameras[c] = extractors[c]->info();
    const SilhouetteMethod method = extractors[c]->info().method;
    mog2 = mog2 || method == SilhouetteMethod::kMog2;  // learns from every frame it sees
    correct[c] = !excluded(c) && ((method == SilhouetteMethod::kLearned && options.multiview_correct_learned) ||
                                  (method == SilhouetteMethod::kPlate && options.multiview_correct_plates));
  }
  // With nothing to correct (every camera has a plate) the check only gives confidences: a
  // coarser hull does (builtin capture, 512x384, 10 cameras x 50 frames: 4.5 s without the
  // check, 12.4 s with it at 128 voxels, 7.4 s at 64).
  const bool any_correct = std::find(correct.begin(), correct.end(), true) != correct.end();
  bool any_plate = false;
  for (int c = 0; c < num_cameras; ++c)
    any_plate = any_plate || (!excluded(c) && extractors[c]->info().method == SilhouetteMethod::kPlate);
  MultiViewOptions multiview = options.plate_free.multiview;
  multiview.threads = options.threads;
  MultiViewOptions check_only = multiview;
  check_only.grid_resolution = std::min(check_only.grid_resolution, 64);
  int start = end_frame;
  for (int c = 0; c < num_cameras; ++c) start = std::min(start, resume(c));
  if (mog2) start = first_frame;

  std::mutex mutex;  // guards progress reports
  std::size_t done = 0, total = 0;
  for (int c = 0; c < num_cameras; ++c) total += static_cast<std::size_t>(end_frame - resume(c));
  std::vector<double> previous_fraction(num_cameras, -1.0);  // of the corrected masks
  std::vector<CameraFrameConfidence> confidences;  // of the camera-frames reaching the sink
  for (int f = start; f < end_frame; ++f) {
    std::vector<Image> images(num_cameras), masks(num_cameras);
    std::vector<MaskSummary> checks(num_cameras);
    std::vector<PersonRegion> people(num_cameras);
    std::vector<int> prior_changed(num_cameras, 0);
    std::vector<Image> unbounded(num_cameras);  // the masks before the prior bounded them
    ParallelFor(num_cameras, options.threads, [&](int c) {
      images[c] = capture.ReadFrame(c, f);
      masks[c] = extractors[c]->Extract(images[c], f, &checks[c], capture.FramePath(c, f));
      checks[c].camera = c;
      if (prior != nullptr && use_prior[c]) {
        Image converted;
        people[c] = prior->Region(c, f, AsRgb8(images[c], &converted), capture.FramePath(c, f));
        unbounded[c] = masks[c];
        prior_changed[c] = ReplaceMask(
            &masks[c], CleanMask(KeepNearPerson(masks[c], people[c]), options.cleanup));
      }
    });
    std::vector<ViewConsistency> views;
    std::vector<Image> hulls, strict_hulls;
    HullUnderside underside;  // of the others' hulls: where feet may stand
    if (options.multiview_check) {
      std::vector<Image> checked(num_cameras);  // excluded cameras: no mask
      for (int c = 0; c < num_cameras; ++c)
        if (!excluded(c)) checked[c] = std::move(masks[c]);
      views = CheckMultiView(capture.rig(), &checked, correct, any_correct ? multiview : check_only, &hulls,
                             &strict_hulls, options.feet.enabled && any_correct ? &underside : nullptr);
      for (int c = 0; c < num_cameras; ++c) {
        if (excluded(c)) continue;
        masks[c] = std::move(checked[c]);
      }
      for (int c = 0; c < num_cameras; ++c)
        if (excluded(c)) views[c] = ViewConsistency{1, 1, 1, 0, 0};
    }
    if (options.plate_claim_inside_hull && !views.empty() && any_plate) {
      // Against a loose hull at full resolution: the legs' skin over a beige floor is lost by
      // several cameras at once, which carves it out of the tolerant hull (samba: the masks'
      // IoU against the truth 0.967 -> 0.991 on frames 30-44).
      std::vector<Image> others(num_cameras);
      for (int c = 0; c < num_cameras; ++c)
        if (!excluded(c)) others[c] = masks[c];
      const std::vector<Image> loose = LooseHullsOfTheOthers(capture.rig(), others, multiview);
      ParallelFor(num_cameras, options.threads, [&](int c) {
        if (excluded(c) || extractors[c]->info().method != SilhouetteMethod::kPlate || loose[c].empty()) return;
        Image converted;
        const Image& rgb = AsRgb8(images[c], &converted);
        const int added = ClaimHighlightsInsideHull(&masks[c], rgb, extractors[c]->model(), loose[c], multiview);
        if (added > 0) views[c].added += added + ReplaceMask(&masks[c], CleanMask(masks[c], options.cleanup));
      });
    }
    // Cameras without a plate: the graph cut, then the feet it took for the floor's shadow.
    std::vector<Image> before_cut;
    std::vector<char> cut(num_cameras, 0);  // written by the cameras' threads: not vector<bool>
    if ((options.grabcut_learned || options.feet.enabled) && !views.empty()) {
      before_cut = masks;
      ParallelFor(num_cameras, options.threads, [&](int c) {
        if (!correct[c] || extractors[c]->info().method != SilhouetteMethod::kLearned) return;
        cut[c] = 1;
        Image converted;
        const Image& rgb = AsRgb8(images[c], &converted);
        // What the prior took away but the others' strict hull holds comes back: a head or a
        // hand that the prior lost in this frame while the other cameras see it.
        if (!unbounded[c].empty() && !strict_hulls[c].empty()) {
          cv::Mat back;
          cv::bitwise_and(AsCvMat(unbounded[c]), AsCvMat(strict_hulls[c]), back);
          cv::bitwise_or(AsCvMat(masks[c]), back, back);
          views[c].added += ReplaceMask(&masks[c], CleanMask(ImageFromCvMat(back), options.cleanup));
        }
        // What the mask holds of the person prior's core stays (an arm the wall's colour).
        if (options.grabcut_learned) {
          Image refined = RefineMaskGrabCut(rgb, masks[c], strict_hulls[c], options.grabcut,
                                            Intersect(people[c].core, masks[c]));
          // What it added beside the body that the background knows goes back (a poster).
          TakeBackKnownBackground(&refined, masks[c], rgb, extractors[c]->model(), strict_hulls[c]);
          views[c].added += ReplaceMask(&masks[c], CleanMask(refined, options.cleanup));
        }
        const int added = RestoreFeetBelowHull(&masks[c], rgb, capture.rig().cameras[c], underside,
                                               extractors[c]->model(), options.feet);
        if (added > 0) views[c].added += added + ReplaceMask(&masks[c], CleanMask(masks[c], options.cleanup));
        // The cut may grow into the room again: kept within reach of the person, or of the others'
        // strict hull.
        if (!people[c].region.empty())
          views[c].removed += ReplaceMask(
              &masks[c], CleanMask(KeepNearPerson(masks[c], people[c], strict_hulls[c]), options.cleanup));
      });
    }
    if (options.recheck_after_cut && std::find(cut.begin(), cut.end(), 1) != cut.end()) {
      std::vector<Image> checked(num_cameras);  // excluded cameras: no mask
      for (int c = 0; c < num_cameras; ++c)
        if (!excluded(c)) checked[c] = std::move(masks[c]);
      const std::vector<int> removed = RemoveRefinementsTheOthersDoNotShare(
          capture.rig(), before_cut, std::vector<bool>(cut.begin(), cut.end()), multiview, &checked);
      for (int c = 0; c < num_cameras; ++c) {
        if (excluded(c)) continue;
        views[c].removed += removed[c];
        masks[c] = std::move(checked[c]);
      }
    }
    for (int c = 0; c < num_cameras; ++c) {
      MaskSummary& check = checks[c];
      const int changed = prior_changed[c] + (views.empty() ? 0 : views[c].added + views[c].removed);
      if (changed > 0) {  // the extractor's checks are of the mask before the changes
        const MaskSummary again = SummarizeMask(masks[c], previous_fraction[c], options);
        check.foreground_fraction = again.foreground_fraction;
        check.empty = again.empty;
        check.full = again.full;
        check.touches_border = again.touches_border;
        check.area_jump = again.area_jump;
      }
      if (!views.empty()) {
        const ViewConsistency& view = views[c];
        check.hull_explained = view.explained;
        check.hull_covered = view.covered;
        check.hull_volume_m3 = view.hull_volume_m3;
        check.corrected_pixels = view.added + view.removed;
        check.confidence = view.confidence;
      }
      previous_fraction[c] = check.foreground_fraction;
      if (check.area_jump) check.confidence *= 0.75;
      if (check.fragmented) check.confidence *= 0.75;
      if (check.empty) check.confidence = 0;
      check.low_confidence = check.confidence < multiview.min_confidence;
      summary.masks[static_cast<std::size_t>(c) * num_frames + (f - first_frame)] = check;
      if (f >= resume(c) && !excluded(c)) confidences.push_back({c, f, check.confidence, check.hull_volume_m3});
    }
    ParallelFor(num_cameras, options.threads, [&](int c) {
      if (f < resume(c)) return;
      if (sink) sink(c, f, images[c], masks[c], checks[c]);
      std::lock_guard<std::mutex> lock(mutex);
      ReportProgress(progress, "silhouettes", ++done, total,
                     capture.rig().cameras[c].name + " frame " + std::to_string(f));
    });
  }
  summary.warnings = capture.warnings();  // what opening the capture adjusted (sensor padding)
  if (!prior_warning.empty()) summary.warnings.push_back(prior_warning);
  for (const CameraSilhouetteInfo& info : summary.cameras)
    for (const std::string& warning : info.warnings) summary.warnings.push_back(info.name + ": " + warning);
  summary.trust =
      SummarizeMaskTrust(capture.rig(), confidences, multiview.min_confidence, multiview.max_hull_volume_m3);
  if (!summary.trust.warning.empty()) summary.warnings.push_back(summary.trust.warning);
  return summary;
}

}  // namespace confluent
