// Tests of Camera (projection, distortion, undistortion, checks) and Rig.

#include "calib/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "core/error.h"

namespace confluent {
namespace {

// A camera at `center` looking at `target` (world z up), OpenCV axes.
Camera DistortedLookAtCamera(const std::string& name, const Eigen::Vector3d& center, const Eigen::Vector3d& target,
                    int width, int height, double focal_px, const Vector5d& dist) {
  Camera camera;
  camera.name = name;
  camera.width = width;
  camera.height = height;
  camera.K << focal_px, 0.0, 0.5 * (width - 1) + 3.7, 0.0, focal_px * 1.002, 0.5 * (height - 1) - 2.1, 0.0, 0.0,
      1.0;
  camera.dist = dist;
  const Eigen::Vector3d forward = (target - center).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  camera.rotation.row(0) = right.transpose();
  camera.rotation.row(1) = down.transpose();
  camera.rotation.row(2) = forward.transpose();
  camera.translation = -camera.rotation * center;
  return camera;
}

Vector5d Dist(double k1, double k2, double p1, double p2, double k3) {
  Vector5d dist;
  dist << k1, k2, p1, p2, k3;
  return dist;
}

// Synthetic cameras with realistic distortion: none, mild, GoPro-like barrel, pincushion.
std::vector<Camera> SyntheticCameras() {
  return {
      DistortedLookAtCamera("pinhole", {3.0, 0.5, 1.5}, {0, 0, 1}, 640, 480, 600.0, Vector5d::Zero()),
      DistortedLookAtCamera("mild", {-2.5, 2.0, 1.8}, {0, 0, 0.9}, 1024, 768, 1100.0, Dist(-0.12, 0.08, 0.0012, -0.0008, -0.01)),
      DistortedLookAtCamera("barrel", {0.2, -3.5, 2.2}, {0, 0, 1}, 1920, 1080, 1000.0, Dist(-0.28, 0.09, 0.0005, 0.0003, -0.002)),
      DistortedLookAtCamera("pincushion", {2.0, 2.0, 0.8}, {0, 0, 1.2}, 800, 600, 1500.0, Dist(0.15, -0.3, -0.001, 0.002, 0.4)),
  };
}

// Pixels on a grid covering the whole image, borders included.
std::vector<Eigen::Vector2d> PixelGrid(const Camera& camera, int steps = 17) {
  std::vector<Eigen::Vector2d> pixels;
  for (int i = 0; i <= steps; ++i)
    for (int j = 0; j <= steps; ++j)
      pixels.emplace_back((camera.width - 1) * double(i) / steps, (camera.height - 1) * double(j) / steps);
  return pixels;
}

TEST(CameraTest, UnprojectThenProjectIsExact) {
  for (const Camera& camera : SyntheticCameras()) {
    for (const Eigen::Vector2d& pixel : PixelGrid(camera)) {
      for (double depth : {0.5, 3.0, 40.0}) {
        const Eigen::Vector3d point = camera.Unproject(pixel, depth);
        EXPECT_NEAR(camera.PointInCamera(point).z(), depth, 1e-9 * depth);
        Eigen::Vector2d reprojected;
        ASSERT_TRUE(camera.ProjectChecked(point, &reprojected));
        EXPECT_LT((reprojected - pixel).norm(), 1e-9) << camera.name << " pixel " << pixel.transpose();
      }
    }
  }
}

TEST(CameraTest, ProjectThenUnprojectIsExact) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-0.8, 0.8);
  for (const Camera& camera : SyntheticCameras()) {
    int tested = 0;
    for (int i = 0; i < 500; ++i) {
      const Eigen::Vector3d point(coord(rng), coord(rng), 1.0 + coord(rng));
      Eigen::Vector2d pixel;
      ASSERT_TRUE(camera.ProjectChecked(point, &pixel));
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > camera.width - 1 || pixel.y() > camera.height - 1) continue;
      ++tested;
      const double depth = camera.PointInCamera(point).z();
      EXPECT_LT((camera.Unproject(pixel, depth) - point).norm(), 1e-9) << camera.name;
      // The ray from the centre through the pixel passes through the point.
      const Eigen::Vector3d to_point = (point - camera.center_in_world()).normalized();
      EXPECT_LT((camera.RayInWorld(pixel) - to_point).norm(), 1e-9) << camera.name;
    }
    EXPECT_GT(tested, 50) << camera.name;
  }
}

TEST(CameraTest, UndistortInvertsDistortInsideTheImage) {
  for (const Camera& camera : SyntheticCameras()) {
    double worst = 0.0;
    for (const Eigen::Vector2d& pixel : PixelGrid(camera, 40)) {
      // An ideal pixel anywhere in the image: distort then undistort.
      const Eigen::Vector2d ideal = (camera.K.inverse() * pixel.homogeneous()).head<2>();
      const Eigen::Vector2d distorted = camera.Distort(ideal);
      worst = std::max(worst, (camera.Undistort(distorted) - ideal).norm());
      // And a distorted pixel anywhere in the image: undistort then distort.
      const Eigen::Vector2d ideal_pixel = camera.UndistortPixel(pixel);
      EXPECT_LT((camera.DistortPixel(ideal_pixel) - pixel).norm(), 1e-9) << camera.name;
    }
    EXPECT_LT(worst, 1e-12) << camera.name;
  }
}

TEST(CameraTest, DistortionMovesPointsAsConfigured) {
  // Barrel distortion (k1 < 0) pulls image points towards the centre, pincushion pushes out.
  const std::vector<Camera> cameras = SyntheticCameras();
  const Eigen::Vector2d p(0.4, -0.3);
  EXPECT_LT(cameras[2].Distort(p).norm(), p.norm());
  EXPECT_GT(cameras[3].Distort(p).norm(), p.norm());
  EXPECT_EQ(cameras[0].Distort(p), p);
  EXPECT_FALSE(cameras[0].has_distortion());
  EXPECT_TRUE(cameras[1].has_distortion());
}

TEST(CameraTest, AgreesWithOpenCvProjectPoints) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  for (const Camera& camera : SyntheticCameras()) {
    std::vector<cv::Point3d> points;
    for (int i = 0; i < 200; ++i) points.emplace_back(coord(rng), coord(rng), 1.0 + coord(rng));
    cv::Mat K(3, 3, CV_64F), dist(1, 5, CV_64F), rotation(3, 3, CV_64F), rvec, tvec(3, 1, CV_64F);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        K.at<double>(r, c) = camera.K(r, c);
        rotation.at<double>(r, c) = camera.rotation(r, c);
      }
      tvec.at<double>(r) = camera.translation[r];
    }
    for (int i = 0; i < 5; ++i) dist.at<double>(i) = camera.dist[i];
    cv::Rodrigues(rotation, rvec);
    std::vector<cv::Point2d> expected;
    cv::projectPoints(points, rvec, tvec, K, dist, expected);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector2d pixel = camera.Project(Eigen::Vector3d(points[i].x, points[i].y, points[i].z));
      EXPECT_NEAR(pixel.x(), expected[i].x, 1e-8) << camera.name;
      EXPECT_NEAR(pixel.y(), expected[i].y, 1e-8) << camera.name;
    }
  }
}

TEST(CameraTest, SkewIsHonoured) {
  Camera camera = SyntheticCameras()[1];
  camera.K(0, 1) = 2.5;
  for (const Eigen::Vector2d& pixel : PixelGrid(camera, 5)) {
    const Eigen::Vector3d point = camera.Unproject(pixel, 2.0);
    EXPECT_LT((camera.Project(point) - pixel).norm(), 1e-9);
  }
  const Eigen::Vector3d point_in_camera(0.1, -0.2, 1.0);
  const Eigen::Vector3d point_in_world = camera.rotation.transpose() * (point_in_camera - camera.translation);
  const Eigen::Vector3d expected = camera.K * camera.Distort(point_in_camera.head<2>()).homogeneous();
  EXPECT_LT((camera.Project(point_in_world) - expected.head<2>()).norm(), 1e-9);
}

TEST(CameraTest, ProjectCheckedRejectsPointsBehind) {
  const Camera camera = SyntheticCameras()[0];
  Eigen::Vector2d pixel;
  const Eigen::Vector3d behind = camera.center_in_world() - camera.optical_axis_in_world();
  EXPECT_FALSE(camera.ProjectChecked(behind, &pixel));
  const Eigen::Vector3d in_front = camera.center_in_world() + camera.optical_axis_in_world();
  ASSERT_TRUE(camera.ProjectChecked(in_front, &pixel));
  EXPECT_NEAR(pixel.x(), camera.K(0, 2), 1e-9);
  EXPECT_NEAR(pixel.y(), camera.K(1, 2), 1e-9);
}

TEST(CameraTest, FieldOfView) {
  Camera camera;
  camera.width = 640;
  camera.height = 480;
  camera.K << 320.0, 0, 319.5, 0, 240.0, 239.5, 0, 0, 1;
  EXPECT_NEAR(camera.horizontal_fov_deg(), 90.0, 1e-9);
  EXPECT_NEAR(camera.vertical_fov_deg(), 90.0, 1e-9);
  camera.K(0, 0) = 640.0;
  EXPECT_NEAR(camera.horizontal_fov_deg(), 2.0 * std::atan(0.5) * 180.0 / M_PI, 1e-9);
}

TEST(CameraTest, CamFromWorldMatchesPointInCamera) {
  const Camera camera = SyntheticCameras()[2];
  const Eigen::Vector3d point(0.3, -0.2, 1.1);
  EXPECT_LT((camera.cam_from_world() * point - camera.PointInCamera(point)).norm(), 1e-12);
  EXPECT_LT((camera.cam_from_world() * camera.center_in_world()).norm(), 1e-12);
}

TEST(CameraTest, CheckAcceptsValidCameras) {
  for (const Camera& camera : SyntheticCameras()) EXPECT_NO_THROW(camera.Check("rig.yml"));
}

// Expects camera.Check to throw an InputError naming the source, the camera and `problem`.
void ExpectCheckFails(const Camera& camera, const std::string& problem) {
  try {
    camera.Check("calib/intri.yml");
    ADD_FAILURE() << "no error for " << problem;
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("calib/intri.yml"), std::string::npos) << message;
    EXPECT_NE(message.find(camera.name), std::string::npos) << message;
    EXPECT_NE(message.find(problem), std::string::npos) << message;
  }
}

TEST(CameraTest, CheckCatchesBadValues) {
  const Camera good = SyntheticCameras()[1];
  Camera bad = good;
  bad.K(0, 0) = std::numeric_limits<double>::quiet_NaN();
  ExpectCheckFails(bad, "NaN");
  bad = good;
  bad.K(1, 1) = 0.0;
  ExpectCheckFails(bad, "focal length");
  bad = good;
  bad.K(0, 0) = -100.0;
  ExpectCheckFails(bad, "focal length");
  bad = good;
  bad.dist[1] = std::numeric_limits<double>::infinity();
  ExpectCheckFails(bad, "distortion");
  bad = good;
  bad.translation.x() = std::numeric_limits<double>::quiet_NaN();
  ExpectCheckFails(bad, "translation");
  bad = good;
  bad.rotation(0, 0) *= 1.01;  // not orthonormal
  ExpectCheckFails(bad, "rotation");
  bad = good;
  bad.rotation.row(0) *= -1.0;  // a reflection: orthonormal but det -1
  ExpectCheckFails(bad, "rotation");
  bad = good;
  bad.width = 0;
  ExpectCheckFails(bad, "size");
}

TEST(RigTest, LookupAndNames) {
  Rig rig;
  rig.cameras = SyntheticCameras();
  EXPECT_EQ(rig.size(), 4);
  EXPECT_EQ(rig.IndexOf("barrel"), 2);
  EXPECT_EQ(rig.IndexOf("nope"), -1);
  EXPECT_EQ(rig.Get("mild").width, 1024);
  EXPECT_EQ(rig.names(), (std::vector<std::string>{"pinhole", "mild", "barrel", "pincushion"}));
  try {
    rig.Get("nope");
    ADD_FAILURE() << "expected UsageError";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("pincushion"), std::string::npos) << error.what();
  }
}

TEST(RigTest, CheckCatchesDuplicateAndEmptyNamesAndBadCameras) {
  Rig rig;
  rig.cameras = SyntheticCameras();
  EXPECT_NO_THROW(rig.Check("x"));
  Rig duplicate = rig;
  duplicate.cameras[3].name = "mild";
  EXPECT_THROW(duplicate.Check("x"), InputError);
  Rig empty_name = rig;
  empty_name.cameras[0].name.clear();
  EXPECT_THROW(empty_name.Check("x"), InputError);
  Rig bad = rig;
  bad.cameras[2].K(0, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(bad.Check("x"), InputError);
}

TEST(RigTest, TransformWorldKeepsProjections) {
  Rig rig;
  rig.cameras = SyntheticCameras();
  const Rig original = rig;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  const double scale = 0.001;  // e.g. metres -> kilometres
  TransformWorld(&rig, rotation, scale);
  EXPECT_NO_THROW(rig.Check());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-0.7, 0.7);
  for (int c = 0; c < rig.size(); ++c) {
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d point_in_old(coord(rng), coord(rng), 1.0 + coord(rng));
      const Eigen::Vector3d point_in_new = scale * rotation * point_in_old;
      const Eigen::Vector2d expected = original.cameras[c].Project(point_in_old);
      EXPECT_LT((rig.cameras[c].Project(point_in_new) - expected).norm(), 1e-8);
    }
    EXPECT_LT((rig.cameras[c].center_in_world() - scale * rotation * original.cameras[c].center_in_world()).norm(),
              1e-12);
  }
}

TEST(UndistortImageTest, MatchesIdealCamera) {
  // A distorted image of a smooth pattern defined on ideal pixels; undistorting must give the
  // pattern back on the ideal pixel grid.
  Camera camera = SyntheticCameras()[2];
  camera.width = 240;
  camera.height = 180;
  camera.K << 130.0, 0, 121.3, 0, 131.0, 88.4, 0, 0, 1;
  auto pattern = [](const Eigen::Vector2d& p) {
    return static_cast<float>(0.5 + 0.25 * std::sin(p.x() / 9.0) + 0.25 * std::cos(p.y() / 7.0));
  };
  Image distorted(camera.width, camera.height, 2, PixelType::kFloat32);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const float value = pattern(camera.UndistortPixel(Eigen::Vector2d(x, y)));
      distorted.at<float>(x, y, 0) = value;
      distorted.at<float>(x, y, 1) = 1.0f - value;
    }
  const Image ideal = UndistortImage(camera, distorted);
  ASSERT_EQ(ideal.width, camera.width);
  ASSERT_EQ(ideal.height, camera.height);
  ASSERT_EQ(ideal.channels, 2);
  double worst = 0.0;
  int inside = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector2d source = camera.DistortPixel(Eigen::Vector2d(x, y));
      if (source.x() < 1 || source.y() < 1 || source.x() > camera.width - 2 || source.y() > camera.height - 2) {
        continue;
      }
      ++inside;
      const double expected = pattern(Eigen::Vector2d(x, y));
      worst = std::max(worst, std::abs(ideal.at<float>(x, y, 0) - expected));
      worst = std::max(worst, std::abs(ideal.at<float>(x, y, 1) - (1.0 - expected)));
    }
  EXPECT_GT(inside, camera.width * camera.height / 2);
  EXPECT_LT(worst, 0.01);  // bilinear interpolation error of the pattern
}

}  // namespace
}  // namespace confluent
