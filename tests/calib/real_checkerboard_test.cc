// Real data (skipped when ../shared/data is absent): utrecht_4cam/camN/checkerboard.avi.
// The board (8x6 inner corners, 115 mm) lies still on the floor for the whole video, small and
// oblique: every frame is the same single view, so the intrinsics can only be a reduced model
// (f and k1), and extrinsics come from the one simultaneous view. The third party's config.xml
// (mm) is the reference; the differences are printed.

#include <gtest/gtest.h>

#include <cstdio>

#include "calib/calibrate.h"
#include "calib/importers.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

struct UtrechtData {
  std::string root;
  CheckerboardSpec board{8, 6, 0.115};
  std::vector<CameraBoardViews> views;
  Rig reference;
};

UtrechtData LoadUtrecht() {
  UtrechtData d;
  d.root = testing::SharedDataPath("real/utrecht_4cam");
  if (d.root.empty()) return d;
  for (int n = 1; n <= 4; ++n) {
    // The board is static: a few frames are as good as all 126.
    CameraBoardViews views = DetectBoardInVideo(d.root + "/cam" + std::to_string(n) + "/checkerboard.avi", d.board,
                                                CheckerboardDetectOptions{}, 60);
    views.name = "cam" + std::to_string(n);
    d.views.push_back(views);
  }
  d.reference = ImportCalibration(CalibFormat::kOpenCvXml, d.root);
  return d;
}

TEST(RealCheckerboard, UtrechtIntrinsicsAndExtrinsics) {
  const UtrechtData data = LoadUtrecht();
  if (data.root.empty()) GTEST_SKIP() << "../shared/data/real/utrecht_4cam is absent";
  int detected = 0, first = -1;
  for (int c = 0; c < 4; ++c) {
    std::printf("%s: board found in %zu of %d frames searched\n", data.views[c].name.c_str(), data.views[c].views.size(),
                data.views[c].frames_searched);
    if (!data.views[c].views.empty()) {
      ++detected;
      if (first < 0) first = c;
    }
  }
  ASSERT_GE(detected, 2) << "the board should be found by at least two cameras";

  // (a) Everything from the video: reduced-model intrinsics per camera, extrinsics.
  CalibrateOptions options;
  options.reference_camera = first;
  CalibrationSummary summary;
  const Rig rig = CalibrateRig(data.board, data.views, options, &summary);
  for (int c = 0; c < 4; ++c) {
    const CameraCalibrationReport& r = summary.cameras[c];
    if (!r.has_intrinsics) continue;
    const Camera& ref = data.reference.Get(r.name);
    std::printf("%s from video alone: views %d distinct %d, RMS %.3f px (reduced model %d), fx %.1f vs config %.1f "
                "(%+.1f%%)\n",
                r.name.c_str(), r.views_detected, r.views_distinct, r.final_rms_px, r.reduced_model,
                rig.cameras[c].K(0, 0), ref.K(0, 0), 100.0 * (rig.cameras[c].K(0, 0) / ref.K(0, 0) - 1.0));
    EXPECT_LT(r.final_rms_px, 0.5) << r.name;
  }

  // (b) Extrinsics with config.xml's intrinsics, compared with config.xml's extrinsics in the
  //     reference camera's frame.
  std::vector<CameraBoardViews> views = data.views;
  for (auto& v : views) v.known_intrinsics = data.reference.Get(v.name);
  CalibrationSummary fixed_summary;
  const Rig fixed = CalibrateRig(data.board, views, options, &fixed_summary);
  const Eigen::Isometry3d ref_from_world = data.reference.Get(views[first].name).cam_from_world();
  int placed = 0;
  for (int c = 0; c < 4; ++c) {
    const CameraCalibrationReport& r = fixed_summary.cameras[c];
    if (!r.placed) {
      std::printf("%s: not placed (%s)\n", r.name.c_str(), fixed_summary.message.c_str());
      continue;
    }
    ++placed;
    const Camera& ref = data.reference.Get(r.name);
    const Eigen::Vector3d ref_centre = ref_from_world * ref.center_in_world();
    const double centre_mm = 1000.0 * (fixed.cameras[c].center_in_world() - ref_centre).norm();
    const Eigen::Matrix3d ref_rotation = ref.rotation * ref_from_world.linear().transpose();
    const double angle_deg = Eigen::AngleAxisd(fixed.cameras[c].rotation * ref_rotation.transpose()).angle() * 180.0 / M_PI;
    std::printf("%s with config.xml intrinsics: RMS %.3f px; centre differs from config.xml by %.1f mm "
                "(baseline to %s %.0f mm), rotation by %.2f deg\n",
                r.name.c_str(), r.final_rms_px, centre_mm, views[first].name.c_str(), 1000.0 * ref_centre.norm(),
                angle_deg);
    EXPECT_LT(r.final_rms_px, 0.5) << r.name;
  }
  EXPECT_GE(placed, 2);
}

}  // namespace
}  // namespace confluent
