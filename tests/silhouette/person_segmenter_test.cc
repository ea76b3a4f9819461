// The learned person prior (silhouette/person_segmenter.h): BlazePose, run in Node, finds the
// studio actor of a generated capture against its ground-truth masks and nobody in the empty
// room; a missing model or a segmenter that dies is named.

#include "silhouette/person_segmenter.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

double MaskIoU(const cv::Mat& a, const cv::Mat& b) {
  const double both = cv::countNonZero(a & b), either = cv::countNonZero(a | b);
  return either > 0 ? both / either : 1.0;
}

TEST(PersonSegmenter, FindsTheStudioActorAndNobodyInTheEmptyRoom) {
  testing::TempDir dir;
  const std::string capture = dir / "capture", truth = dir / "truth";
  // 512x384: the actor is about 250 pixels tall, as in the motion suite's small captures.
  const auto synth = testing::RunConfluent({"synth", "--out", capture, "--gt", truth, "--width", "512", "--height",
                                            "384", "--frames", "1", "--cameras", "6", "--heldout", "0"});
  ASSERT_EQ(synth.exit_code, 0) << synth.stderr_text;
  PersonSegmenter segmenter;
  for (const auto& entry : fs::directory_iterator(capture + "/images")) {
    const std::string camera = entry.path().filename().string();
    const Image image = ReadImage((entry.path() / "000000.png").string());
    const cv::Mat expected = cv::imread(truth + "/masks/" + camera + "/000000.png", cv::IMREAD_GRAYSCALE) > 127;
    ASSERT_FALSE(expected.empty()) << camera;
    const PersonSegmentation person = segmenter.Segment(image, camera);
    const double iou = MaskIoU(AsCvMat(person.mask), expected);
    std::printf("%s: IoU %.3f, presence %.2f\n", camera.c_str(), iou, person.presence);
    EXPECT_GE(iou, 0.92) << camera;  // 0.951 to 0.967 measured
    EXPECT_GE(person.presence, 0.5) << camera;
    // The hips and shoulders land on the actor.
    for (int landmark : {11, 12, 23, 24}) {
      const Eigen::Vector3f& p = person.landmarks[landmark];
      cv::Mat near_actor;
      cv::dilate(expected, near_actor, cv::Mat(), cv::Point(-1, -1), 3);
      ASSERT_TRUE(p.x() >= 0 && p.y() >= 0 && p.x() < image.width && p.y() < image.height) << camera << " " << landmark;
      EXPECT_GT(near_actor.at<std::uint8_t>(static_cast<int>(p.y()), static_cast<int>(p.x())), 0)
          << camera << " landmark " << landmark;
    }
    const Image plate = ReadImage(capture + "/background/" + camera + ".png");
    const PersonSegmentation nobody = segmenter.Segment(plate, camera);
    const double pixels = static_cast<double>(plate.width) * plate.height;
    std::printf("%s empty room: %.4f of the image, presence %.2f\n", camera.c_str(),
                cv::countNonZero(AsCvMat(nobody.mask)) / pixels, nobody.presence);
    EXPECT_LT(cv::countNonZero(AsCvMat(nobody.mask)), 0.01 * pixels) << camera;
  }
}

TEST(PersonSegmenter, MissingModelIsNamed) {
  testing::TempDir dir;
  testing::WriteFile(dir / "segment.js", "process.exit(0);\n");
  PersonSegmenterOptions options;
  options.script = dir / "segment.js";
  try {
    PersonSegmenter segmenter(options);
    ADD_FAILURE() << "started without a model";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("model"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("install-deps"), std::string::npos) << error.what();
  }
}

TEST(PersonSegmenter, SegmenterThatDiesIsReportedWithItsError) {
  testing::TempDir dir;
  testing::WriteFile(dir / "models/blazepose-full.bin", "");
  fs::create_directories(dir / "node_modules/@tensorflow/tfjs-backend-wasm");
  testing::WriteFile(dir / "segment.js", "console.error('no WebAssembly here'); process.exit(5);\n");
  PersonSegmenterOptions options;
  options.script = dir / "segment.js";
  try {
    PersonSegmenter segmenter(options);
    ADD_FAILURE() << "a segmenter that exits at once was taken as ready";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("exit status 5"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("no WebAssembly here"), std::string::npos) << error.what();
  }
  // A segmenter that answers nothing once started.
  testing::WriteFile(dir / "segment.js", "process.stdout.write('CPSEG001'); process.stdin.once('data', () => process.exit(7));\n");
  PersonSegmenter silent(options);
  const Image image(160, 120, 3);
  try {
    silent.Segment(image, "cam00/000000.png");
    ADD_FAILURE() << "no answer was taken as one";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cam00/000000.png"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("exit status 7"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace confluent
