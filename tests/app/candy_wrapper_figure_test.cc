// The candy-wrapper figure of report section 4.3: a forearm (tube) twisted about its own axis
// to 270 degrees by its wrist markers, deformed with each singularity handling, rendered side
// by side. Vertex colours are stripes by the reference angle around the axis, so the twist can
// be seen. The test checks the pictures: without handling the tube pinches (the blended
// quaternions nearly cancel mid-arm); with the intermediate reference or the SLERP paths it does
// not. The figure goes to $CONFLUENT_FIGURES_DIR/candy_wrapper.png when that is set.

#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "deform/confluent_motion.h"
#include "render/renderer.h"
#include "tests/deform/test_geometry.h"
#include "tests/render/renderer_test_util.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

struct Panel {
  std::string label;
  ConfluentMotionOptions options;
  cv::Mat image;                 // BGR
  double narrowest_ratio = 0.0;  // narrowest silhouette width mid-arm / width at the elbow
};

// Silhouette width in pixels of image row y.
int RowWidth(const Image& mask, int y) {
  int first = -1, last = -1;
  for (int x = 0; x < mask.width; ++x)
    if (mask.at<std::uint8_t>(x, y) > 0) {
      if (first < 0) first = x;
      last = x;
    }
  return first < 0 ? 0 : last - first + 1;
}

TEST(CandyWrapperFigure, HandlingKeepsTheTwistedForearmFromPinching) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  Mesh scan = testing::MakeTube(0.04, 0.6, 60, 24, 0.13);
  scan.colors.resize(scan.num_vertices(), 3);
  for (int v = 0; v < scan.num_vertices(); ++v) {
    const double angle = std::atan2(scan.vertices(v, 1), scan.vertices(v, 0));
    const bool stripe = static_cast<int>(std::floor(4.0 * (angle + M_PI) / M_PI)) % 2 == 0;
    scan.colors.row(v) = stripe ? Eigen::RowVector3f(0.85f, 0.55f, 0.2f) : Eigen::RowVector3f(0.2f, 0.45f, 0.8f);
  }
  const Correspondences pairs = testing::TubePairs(template_mesh, scan, {0.05, 0.1, 0.5, 0.55}, 4, 0.04, 0.3);
  std::vector<Panel> panels(4);
  panels[0].label = "hemisphere signs";
  panels[0].options.intermediate_reference = false;
  panels[0].options.temporal_signs = false;
  panels[1].label = "temporal signs";
  panels[1].options.intermediate_reference = false;
  panels[2].label = "intermediate ref.";
  panels[3].label = "SLERP paths";
  panels[3].options.slerp_paths = true;

  // Side view of the vertical tube, elbow (z = 0) at the bottom.
  const Camera camera = render_test::LookAtTestCamera(Eigen::Vector3d(1.2, -0.5, 0.3), Eigen::Vector3d(0, 0, 0.3),
                                                  220, 440, 650.0);
  const int elbow_row = static_cast<int>(std::lround(camera.Project(Eigen::Vector3d(0, 0, 0.05)).y()));
  const int row_low = static_cast<int>(std::lround(camera.Project(Eigen::Vector3d(0, 0, 0.15)).y()));
  const int row_high = static_cast<int>(std::lround(camera.Project(Eigen::Vector3d(0, 0, 0.45)).y()));
  MeshRenderer renderer;
  const int handle = renderer.AddMesh(scan, "scan");
  RenderRequest request;
  request.silhouette = true;
  request.shading.background = Eigen::Vector3d(1, 1, 1);
  for (Panel& panel : panels) {
    ConfluentMotion motion(scan, template_mesh, pairs, panel.options);
    RowMatrixX3d deformed;
    for (int degrees = 0; degrees <= 270; degrees += 10)  // frame by frame, as in a sequence
      deformed = motion.Deform(testing::RotateAbove(
          template_mesh.vertices, 0.3, Eigen::AngleAxisd(degrees * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix()));
    renderer.UpdateVertices(handle, deformed);
    const RenderResult result = renderer.Render(camera, request);
    const int elbow_width = RowWidth(result.silhouette, elbow_row);
    ASSERT_GT(elbow_width, 10);
    int narrowest = elbow_width;
    for (int y = std::min(row_low, row_high); y <= std::max(row_low, row_high); ++y)
      narrowest = std::min(narrowest, RowWidth(result.silhouette, y));
    panel.narrowest_ratio = static_cast<double>(narrowest) / elbow_width;
    cv::Mat rgb(result.color.height, result.color.width, CV_8UC3, const_cast<std::uint8_t*>(result.color.data.data()));
    cv::cvtColor(rgb, panel.image, cv::COLOR_RGB2BGR);
    char text[64];
    std::snprintf(text, sizeof(text), "min width %.0f%%", 100 * panel.narrowest_ratio);
    cv::putText(panel.image, panel.label, {6, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
    cv::putText(panel.image, text, {6, 38}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
    std::printf("%-18s narrowest width mid-arm %.2f of the elbow's\n", panel.label.c_str(), panel.narrowest_ratio);
  }
  cv::Mat figure;
  std::vector<cv::Mat> images;
  for (const Panel& panel : panels) images.push_back(panel.image);
  cv::hconcat(images, figure);
  cv::putText(figure, "forearm twisted to 270 deg by its wrist markers", {6, figure.rows - 10},
              cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  testing::TempDir dir;
  const char* figures = std::getenv("CONFLUENT_FIGURES_DIR");
  const std::string path = (figures ? std::string(figures) : dir.path()) + "/candy_wrapper.png";
  ASSERT_TRUE(cv::imwrite(path, figure)) << path;

  // Temporal signs without handling: the blended quaternions nearly cancel and the arm pinches.
  EXPECT_LT(panels[1].narrowest_ratio, 0.75);
  // Both handlings keep the cross-section.
  EXPECT_GT(panels[2].narrowest_ratio, panels[1].narrowest_ratio + 0.1);
  EXPECT_GT(panels[3].narrowest_ratio, panels[1].narrowest_ratio + 0.1);
}

}  // namespace
}  // namespace confluent
