// Tests of the calibration importers: each format is written by the test from a known rig,
// imported, and compared with the rig by projecting points. Real files are checked for
// plausibility when ../shared/data is present.

#include "calib/importers.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::SharedDataPath;
using testing::TempDir;
using testing::WriteFile;

// `count` cameras on a ring of radius 3 m around (0, 0, 1), world z up, with distortion.
Rig GroundTruthRig(int count = 5) {
  Rig rig;
  for (int i = 0; i < count; ++i) {
    const double angle = 2.0 * M_PI * i / count + 0.2;
    const Eigen::Vector3d center(3.0 * std::cos(angle), 3.0 * std::sin(angle), 1.5 + 0.2 * i);
    const Eigen::Vector3d target(0.1 * i, -0.05 * i, 1.0);
    Camera camera;
    char name[16];
    std::snprintf(name, sizeof(name), "cam%d", i);
    camera.name = name;
    camera.width = 640 + 16 * i;
    camera.height = 480;
    camera.K << 520.0 + 15.0 * i, 0.0, 0.5 * (camera.width - 1) + 2.5 * i, 0.0, 522.0 + 14.0 * i, 241.3 - i, 0, 0, 1;
    camera.dist << -0.2 + 0.02 * i, 0.05 + 0.01 * i, 0.001 * (i - 2), -0.0005 * i, 0.0;
    const Eigen::Vector3d forward = (target - center).normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    camera.rotation.row(0) = right.transpose();
    camera.rotation.row(1) = down.transpose();
    camera.rotation.row(2) = forward.transpose();
    camera.translation = -camera.rotation * center;
    rig.cameras.push_back(camera);
  }
  return rig;
}

// Largest pixel distance between the projections of points near (0, 0, 1) by the two rigs.
double MaxProjectionDifference(const Rig& expected, const Rig& actual) {
  EXPECT_EQ(expected.names(), actual.names());
  if (expected.names() != actual.names()) return 1e9;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-0.6, 0.6);
  double worst = 0.0;
  for (int c = 0; c < expected.size(); ++c) {
    EXPECT_EQ(expected.cameras[c].width, actual.cameras[c].width);
    EXPECT_EQ(expected.cameras[c].height, actual.cameras[c].height);
    for (int i = 0; i < 100; ++i) {
      const Eigen::Vector3d point(coord(rng), coord(rng), 1.0 + coord(rng));
      worst = std::max(worst, (expected.cameras[c].Project(point) - actual.cameras[c].Project(point)).norm());
    }
    worst = std::max(worst, (expected.cameras[c].center_in_world() - actual.cameras[c].center_in_world()).norm() * 1e3);
  }
  return worst;
}

std::string Num(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

// Expects `run` to throw InputError whose message contains `part`.
template <typename Function>
void ExpectInputError(Function run, const std::string& part) {
  try {
    run();
    ADD_FAILURE() << "no error; expected " << part;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(part), std::string::npos) << error.what();
  }
}

// ------------------------------------------------------------------------------------------
// COLMAP

// Writes cameras.txt/images.txt for `rig`, one camera model per camera, translations
// multiplied by `units_per_metre`. Each camera's intrinsics are simplified to what its model
// can represent (and written back to `rig`).
void WriteColmap(Rig* rig, const std::string& dir, double units_per_metre = 1.0) {
  const char* models[] = {"SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV"};
  std::ostringstream cameras, images;
  cameras << "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
  images << "# Image list with two lines of data per image:\n";
  for (int i = 0; i < rig->size(); ++i) {
    Camera& camera = rig->cameras[i];
    const std::string model = models[i % 5];
    camera.K(0, 1) = 0.0;
    if (model == "SIMPLE_PINHOLE" || model == "SIMPLE_RADIAL" || model == "RADIAL") camera.K(1, 1) = camera.K(0, 0);
    if (model == "SIMPLE_PINHOLE" || model == "PINHOLE") camera.dist.setZero();
    if (model == "SIMPLE_RADIAL") camera.dist.tail<4>().setZero();
    if (model == "RADIAL") camera.dist.tail<3>().setZero();
    if (model == "OPENCV") camera.dist[4] = 0.0;
    const double fx = camera.K(0, 0), fy = camera.K(1, 1);
    const double cx = camera.K(0, 2) + 0.5, cy = camera.K(1, 2) + 0.5;  // COLMAP pixel centres
    const Vector5d& d = camera.dist;
    cameras << i + 1 << " " << model << " " << camera.width << " " << camera.height;
    if (model == "SIMPLE_PINHOLE") cameras << " " << Num(fx) << " " << Num(cx) << " " << Num(cy);
    if (model == "PINHOLE") cameras << " " << Num(fx) << " " << Num(fy) << " " << Num(cx) << " " << Num(cy);
    if (model == "SIMPLE_RADIAL") cameras << " " << Num(fx) << " " << Num(cx) << " " << Num(cy) << " " << Num(d[0]);
    if (model == "RADIAL")
      cameras << " " << Num(fx) << " " << Num(cx) << " " << Num(cy) << " " << Num(d[0]) << " " << Num(d[1]);
    if (model == "OPENCV")
      cameras << " " << Num(fx) << " " << Num(fy) << " " << Num(cx) << " " << Num(cy) << " " << Num(d[0]) << " "
              << Num(d[1]) << " " << Num(d[2]) << " " << Num(d[3]);
    cameras << "\n";
    const Eigen::Quaterniond q(camera.rotation);
    const Eigen::Vector3d t = camera.translation * units_per_metre;
    images << i + 10 << " " << Num(q.w()) << " " << Num(q.x()) << " " << Num(q.y()) << " " << Num(q.z()) << " "
           << Num(t.x()) << " " << Num(t.y()) << " " << Num(t.z()) << " " << i + 1 << " " << camera.name << ".jpg\n";
    if (i % 2 == 0) {
      images << "12.5 30.25 -1 400.0 17.0 3\n";
    } else {
      images << "\n";  // no 2D points
    }
  }
  WriteFile(dir + "/cameras.txt", cameras.str());
  WriteFile(dir + "/images.txt", images.str());
}

TEST(ColmapImportTest, MatchesGroundTruthForEveryModel) {
  TempDir dir;
  Rig truth = GroundTruthRig();
  WriteColmap(&truth, dir.path());
  const Rig imported = ImportCalibration(CalibFormat::kColmap, dir.path());
  EXPECT_LT(MaxProjectionDifference(truth, imported), 1e-6);
  // The same through the cameras.txt path, with translations in millimetres.
  TempDir mm;
  Rig truth_mm = GroundTruthRig();
  WriteColmap(&truth_mm, mm.path(), 1000.0);
  ImportOptions options;
  options.metres_per_unit = 0.001;
  const Rig imported_mm = ImportCalibration(CalibFormat::kColmap, mm / "cameras.txt", options);
  EXPECT_LT(MaxProjectionDifference(truth_mm, imported_mm), 1e-6);
}

TEST(ColmapImportTest, PrincipalPointMovesByHalfAPixel) {
  TempDir dir;
  WriteFile(dir / "cameras.txt", "1 PINHOLE 100 80 90 90 50 40\n");
  WriteFile(dir / "images.txt", "1 1 0 0 0 0 0 2 1 a.png\n\n");
  const Rig rig = ImportCalibration(CalibFormat::kColmap, dir.path());
  ASSERT_EQ(rig.size(), 1);
  EXPECT_EQ(rig.cameras[0].name, "a");
  EXPECT_DOUBLE_EQ(rig.cameras[0].K(0, 2), 49.5);  // the image centre of a 100-pixel-wide image
  EXPECT_DOUBLE_EQ(rig.cameras[0].K(1, 2), 39.5);
}

TEST(ColmapImportTest, BadInputNamesTheFile) {
  TempDir dir;
  WriteFile(dir / "cameras.txt", "1 OPENCV_FISHEYE 100 80 90 90 50 40 0 0 0 0\n");
  WriteFile(dir / "images.txt", "1 1 0 0 0 0 0 2 1 a.png\n\n");
  ExpectInputError([&] { ImportCalibration(CalibFormat::kColmap, dir.path()); }, "unsupported COLMAP camera model");
  WriteFile(dir / "cameras.txt", "1 PINHOLE 100 80 nan 90 50 40\n");
  ExpectInputError([&] { ImportCalibration(CalibFormat::kColmap, dir.path()); }, "cameras.txt");
  WriteFile(dir / "cameras.txt", "1 PINHOLE 100 80 90 90 50 40\n");
  WriteFile(dir / "images.txt", "1 1 0 0 0 0 0 2 7 a.png\n\n");
  ExpectInputError([&] { ImportCalibration(CalibFormat::kColmap, dir.path()); }, "camera id 7 is not in cameras.txt");
  WriteFile(dir / "images.txt", "1 1 0 0 0 0 0 2 1 x/a.png\n\n2 1 0 0 0 0 0 2 1 x/a.png\n\n");
  ExpectInputError([&] { ImportCalibration(CalibFormat::kColmap, dir.path()); }, "not unique");
}

TEST(ColmapImportTest, RepeatedStemsUseFolderNames) {
  TempDir dir;
  WriteFile(dir / "cameras.txt", "1 PINHOLE 100 80 90 90 50 40\n");
  WriteFile(dir / "images.txt", "1 1 0 0 0 0 0 2 1 left/000000.png\n\n2 1 0 0 0 1 0 2 1 right/000000.png\n\n");
  const Rig rig = ImportCalibration(CalibFormat::kColmap, dir.path());
  EXPECT_EQ(rig.names(), (std::vector<std::string>{"left", "right"}));
}

// ------------------------------------------------------------------------------------------
// transforms.json

// transforms.json of `rig`: per-frame intrinsics, OpenGL camera-to-world matrices.
std::string TransformsJson(const Rig& rig, bool with_size = true) {
  std::ostringstream out;
  out << "{\n  \"camera_model\": \"OPENCV\",\n  \"frames\": [\n";
  for (int i = 0; i < rig.size(); ++i) {
    const Camera& camera = rig.cameras[i];
    Eigen::Matrix4d world_from_camera = Eigen::Matrix4d::Identity();
    world_from_camera.topLeftCorner<3, 3>() =
        camera.rotation.transpose() * Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
    world_from_camera.topRightCorner<3, 1>() = camera.center_in_world();
    out << "    {\"file_path\": \"images/" << camera.name << ".png\", ";
    if (with_size) out << "\"w\": " << camera.width << ", \"h\": " << camera.height << ", ";
    out << "\"fl_x\": " << Num(camera.K(0, 0)) << ", \"fl_y\": " << Num(camera.K(1, 1))
        << ", \"cx\": " << Num(camera.K(0, 2) + 0.5) << ", \"cy\": " << Num(camera.K(1, 2) + 0.5)
        << ", \"k1\": " << Num(camera.dist[0]) << ", \"k2\": " << Num(camera.dist[1])
        << ", \"p1\": " << Num(camera.dist[2]) << ", \"p2\": " << Num(camera.dist[3]) << ",\n     \"transform_matrix\": [";
    for (int r = 0; r < 4; ++r) {
      out << (r ? ", " : "") << "[";
      for (int c = 0; c < 4; ++c) out << (c ? ", " : "") << Num(world_from_camera(r, c));
      out << "]";
    }
    out << "]}" << (i + 1 < rig.size() ? "," : "") << "\n";
  }
  out << "  ]\n}\n";
  return out.str();
}

TEST(TransformsJsonImportTest, MatchesGroundTruthInAYUpWorld) {
  TempDir dir;
  const Rig truth = GroundTruthRig();
  // The file's world is Y up: point_in_file = R^T point_in_truth.
  Rig y_up = truth;
  TransformWorld(&y_up, RotationToZUp("+y").transpose(), 1.0);
  WriteFile(dir / "transforms.json", TransformsJson(y_up));
  ImportOptions options;
  options.up_axis = "+y";
  const Rig imported = ImportCalibration(CalibFormat::kTransformsJson, dir.path(), options);
  EXPECT_LT(MaxProjectionDifference(truth, imported), 1e-6);
  // Without the up-axis option the world stays Y up and the projections differ.
  const Rig not_rotated = ImportCalibration(CalibFormat::kTransformsJson, dir / "transforms.json");
  EXPECT_GT(MaxProjectionDifference(truth, not_rotated), 10.0);
}

TEST(TransformsJsonImportTest, BlenderStyleWithCameraAngleAndImageSize) {
  TempDir dir;
  // Blender synthetic scenes: global camera_angle_x, no size (read from the image), no
  // extension in file_path.
  const double angle_x = 0.6911112070083618;
  const int width = 80, height = 60;
  std::filesystem::create_directories(dir / "train");
  cv::imwrite(dir / "train/r_0.png", cv::Mat(height, width, CV_8UC3, cv::Scalar(10, 20, 30)));
  cv::imwrite(dir / "train/r_1.png", cv::Mat(height, width, CV_8UC3, cv::Scalar(10, 20, 30)));
  WriteFile(dir / "transforms_train.json",
            "{\"camera_angle_x\": " + Num(angle_x) +
                ", \"frames\": ["
                "{\"file_path\": \"./train/r_0\", \"transform_matrix\": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]},"
                "{\"file_path\": \"./train/r_1\", \"transform_matrix\": [[0,0,1,4],[1,0,0,0],[0,1,0,0],[0,0,0,1]]}]}");
  ASSERT_TRUE(std::filesystem::exists(dir / "train/r_0.png"));
  const Rig rig = ImportCalibration(CalibFormat::kTransformsJson, dir / "transforms_train.json");
  ASSERT_EQ(rig.names(), (std::vector<std::string>{"r_0", "r_1"}));
  const Camera& camera = rig.cameras[0];
  EXPECT_EQ(camera.width, width);
  EXPECT_EQ(camera.height, height);
  EXPECT_NEAR(camera.K(0, 0), 0.5 * width / std::tan(0.5 * angle_x), 1e-9);
  EXPECT_NEAR(camera.K(1, 1), camera.K(0, 0), 1e-9);
  EXPECT_NEAR(camera.K(0, 2), 0.5 * (width - 1), 1e-12);
  // Camera 0 sits at (0, 0, 4) looking down -z (OpenGL): it sees the origin in the centre.
  EXPECT_LT((camera.center_in_world() - Eigen::Vector3d(0, 0, 4)).norm(), 1e-12);
  EXPECT_LT((camera.Project(Eigen::Vector3d::Zero()) - camera.K.col(2).head<2>()).norm(), 1e-9);
  // Its image y axis points down, i.e. along world -y (OpenGL y is up).
  EXPECT_GT(camera.Project(Eigen::Vector3d(0, -0.1, 0)).y(), camera.K(1, 2));
  // Camera 1 sits at (4, 0, 0) looking along -x and also sees the origin in the centre.
  EXPECT_LT((rig.cameras[1].Project(Eigen::Vector3d::Zero()) - rig.cameras[1].K.col(2).head<2>()).norm(), 1e-9);
}

TEST(TransformsJsonImportTest, MissingSizeAndBadJsonAreErrors) {
  TempDir dir;
  const Rig truth = GroundTruthRig(2);
  WriteFile(dir / "transforms.json", TransformsJson(truth, false));
  ExpectInputError([&] { ImportCalibration(CalibFormat::kTransformsJson, dir.path()); }, "image size unknown");
  ImportOptions options;
  options.default_width = 640;
  options.default_height = 480;
  EXPECT_EQ(ImportCalibration(CalibFormat::kTransformsJson, dir.path(), options).cameras[0].width, 640);
  WriteFile(dir / "transforms.json", "{\"frames\": [ {\"transform_matrix\": ");
  ExpectInputError([&] { ImportCalibration(CalibFormat::kTransformsJson, dir.path()); }, "invalid JSON");
}

// ------------------------------------------------------------------------------------------
// Qualisys

// A .qca.txt for `rig` with the conventions of Pose2Sim's read_qca (see importers.cc).
std::string QualisysXml(const Rig& rig) {
  std::ostringstream out;
  out << "<?xml version='1.0' encoding='ASCII'?>\n<calibration type=\"regular\">\n  <cameras>\n";
  const int left = 8, top = 4;
  for (const Camera& camera : rig.cameras) {
    const Eigen::Matrix3d r = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal() * camera.rotation;
    const Eigen::Vector3d center = camera.center_in_world() * 1000.0;
    out << "    <camera active=\"1\" model=\"Miqus Video\" serial=\"" << camera.name << "\">\n"
        << "      <fov_marker bottom=\"9\" left=\"0\" right=\"9\" top=\"0\"/>\n"
        << "      <fov_video bottom=\"" << top + camera.height - 1 << "\" left=\"" << left << "\" right=\""
        << left + camera.width - 1 << "\" top=\"" << top << "\"/>\n      <transform";
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out << " r" << i + 1 << j + 1 << "=\"" << Num(r(i, j)) << "\"";
    out << " x=\"" << Num(center.x()) << "\" y=\"" << Num(center.y()) << "\" z=\"" << Num(center.z()) << "\"/>\n"
        << "      <intrinsic centerPointU=\"" << Num((camera.K(0, 2) + left) * 64) << "\" centerPointV=\""
        << Num((camera.K(1, 2) + top) * 64) << "\" focalLengthU=\"" << Num(camera.K(0, 0) * 64)
        << "\" focalLengthV=\"" << Num(camera.K(1, 1) * 64) << "\" radialDistortion1=\"" << Num(camera.dist[0] * 64)
        << "\" radialDistortion2=\"" << Num(camera.dist[1] * 64) << "\" radialDistortion3=\"0.000000\" skew=\"0\""
        << " tangentalDistortion1=\"" << Num(camera.dist[2] * 64) << "\" tangentalDistortion2=\""
        << Num(camera.dist[3] * 64) << "\"/>\n    </camera>\n";
  }
  // A marker-only camera, which is not imported.
  out << "    <camera active=\"1\" model=\"Miqus M3\" serial=\"marker9\"><fov_video bottom=\"1\" left=\"0\" "
         "right=\"1\" top=\"0\"/></camera>\n  </cameras>\n</calibration>\n";
  return out.str();
}

TEST(QualisysImportTest, MatchesGroundTruth) {
  TempDir dir;
  const Rig truth = GroundTruthRig(4);
  WriteFile(dir / "Calib.qca.txt", QualisysXml(truth));
  const Rig imported = ImportCalibration(CalibFormat::kQualisys, dir / "Calib.qca.txt");  // mm by default
  EXPECT_LT(MaxProjectionDifference(truth, imported), 1e-6);
}

TEST(QualisysImportTest, MissingAttributeIsAnError) {
  TempDir dir;
  std::string text = QualisysXml(GroundTruthRig(2));
  text.replace(text.find("focalLengthU"), 12, "focalLengthX");
  WriteFile(dir / "Calib.qca.txt", text);
  ExpectInputError([&] { ImportCalibration(CalibFormat::kQualisys, dir / "Calib.qca.txt"); },
                   "camera cam0: missing attribute focalLengthU");
}

// ------------------------------------------------------------------------------------------
// Plain text (tsinghua_lkB style)

TEST(PlainTextImportTest, MatchesGroundTruthInDecimetres) {
  TempDir dir;
  Rig truth = GroundTruthRig();
  std::ostringstream out;
  for (int i = 0; i < truth.size(); ++i) {
    Camera& camera = truth.cameras[i];
    camera.name = "cam0" + std::to_string(i);
    camera.width = 1024;
    camera.height = 768;
    camera.dist.tail<3>().setZero();  // the format stores k1 k2 only
    camera.K(0, 1) = -0.7;            // with skew
    out << i << "\n";
    for (int r = 0; r < 3; ++r) out << Num(camera.K(r, 0)) << "\t" << Num(camera.K(r, 1)) << "\t" << Num(camera.K(r, 2)) << "\n";
    out << Num(camera.dist[0]) << "\t" << Num(camera.dist[1]) << "\n";
    for (int r = 0; r < 3; ++r)
      out << Num(camera.rotation(r, 0)) << "\t" << Num(camera.rotation(r, 1)) << "\t" << Num(camera.rotation(r, 2))
          << "\t" << Num(camera.translation[r] * 10.0) << "\n";
    out << "\n";
  }
  WriteFile(dir / "CalibParams.txt", out.str());
  ImportOptions options;
  options.metres_per_unit = 0.1;
  const Rig imported = ImportCalibration(CalibFormat::kPlainText, dir / "CalibParams.txt", options);
  EXPECT_LT(MaxProjectionDifference(truth, imported), 1e-6);
  // A truncated file names the problem.
  std::string text = out.str();
  WriteFile(dir / "CalibParams.txt", text.substr(0, text.size() - 20));
  ExpectInputError([&] { ImportCalibration(CalibFormat::kPlainText, dir / "CalibParams.txt", options); },
                   "expected blocks of 24 numbers");
}

// ------------------------------------------------------------------------------------------
// OpenCV XML

void WriteOpenCvXml(const Camera& camera, const std::string& path, bool with_size) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  cv::FileStorage storage(path, cv::FileStorage::WRITE);
  cv::Mat K(3, 3, CV_64F), dist(1, 5, CV_64F), rotation(3, 3, CV_64F), rvec, tvec(3, 1, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      K.at<double>(r, c) = camera.K(r, c);
      rotation.at<double>(r, c) = camera.rotation(r, c);
    }
    tvec.at<double>(r) = camera.translation[r] * 1000.0;  // mm
  }
  for (int i = 0; i < 5; ++i) dist.at<double>(i) = camera.dist[i];
  cv::Rodrigues(rotation, rvec);
  storage << "CameraMatrix" << K << "DistortionCoeffs" << dist << "Rotation" << rvec << "Translation" << tvec;
  if (with_size) storage << "image_width" << camera.width << "image_height" << camera.height;
}

TEST(OpenCvXmlImportTest, FolderOfCameraFolders) {
  TempDir dir;
  Rig truth = GroundTruthRig(4);
  for (auto& camera : truth.cameras) {
    camera.dist[4] = -0.01;
    WriteOpenCvXml(camera, dir / (camera.name + "/config.xml"), camera.name != "cam2");
    // An intrinsics-only file in the same folder is ignored.
    cv::FileStorage other(dir / (camera.name + "/intrinsics.xml"), cv::FileStorage::WRITE);
    other << "CameraMatrix" << cv::Mat::eye(3, 3, CV_64F);
  }
  // cam2 stores no size: it is read from an image beside the file.
  cv::imwrite(dir / "cam2/frame.png", cv::Mat(truth.cameras[2].height, truth.cameras[2].width, CV_8UC1, cv::Scalar(0)));
  const Rig imported = ImportCalibration(CalibFormat::kOpenCvXml, dir.path());  // mm by default
  EXPECT_LT(MaxProjectionDifference(truth, imported), 1e-6);
  // One file is one camera, named after its folder when the file is called config.xml.
  const Rig single = ImportCalibration(CalibFormat::kOpenCvXml, dir / "cam1/config.xml");
  ASSERT_EQ(single.size(), 1);
  EXPECT_EQ(single.cameras[0].name, "cam1");
}

// The convention of rvec/tvec, checked against OpenCV itself rather than against our writer:
// a checkerboard (corners in mm, lying on the floor) is seen by a camera 2 m above the floor;
// cv::solvePnP on its pixels gives rvec/tvec exactly as a third-party OpenCV calibration
// (utrecht_4cam config.xml) stores them. The import must reproduce the pixels of the board
// corners given in metres, and, since the board's z axis (x cross y, rows across the floor)
// points into the floor, place the camera at z = -2 m; with up axis -z it is at z = +2 m.
TEST(OpenCvXmlImportTest, RvecTvecFromSolvePnpAreWorldToCameraInMillimetres) {
  TempDir dir;
  Camera camera = LookAtCamera("cam1", Eigen::Vector3d(2.5, -1.0, 2.0), Eigen::Vector3d(0.4, 0.3, 0.0), 644, 486, 490.0);
  camera.dist << -0.3, 0.15, 0.001, -0.0005, -0.05;
  // Board on the floor: x along the rows, y across them; corner (i, j) at (i, j) * 115 mm.
  // Board frame = world frame of the file, with z = x cross y = down.
  const Eigen::Matrix3d board_in_zup = Eigen::Vector3d(1, -1, -1).asDiagonal();  // board axes in a z-up world
  std::vector<cv::Point3d> corners_mm;
  std::vector<cv::Point2d> pixels;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d in_board(i * 115.0, j * 115.0, 0.0);
      corners_mm.emplace_back(in_board.x(), in_board.y(), in_board.z());
      const Eigen::Vector2d pixel = camera.Project(board_in_zup * in_board / 1000.0);
      pixels.emplace_back(pixel.x(), pixel.y());
    }
  cv::Mat K(3, 3, CV_64F), dist(1, 5, CV_64F), rvec, tvec;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) K.at<double>(r, c) = camera.K(r, c);
  for (int i = 0; i < 5; ++i) dist.at<double>(i) = camera.dist[i];
  ASSERT_TRUE(cv::solvePnP(corners_mm, pixels, K, dist, rvec, tvec, false, cv::SOLVEPNP_ITERATIVE));
  {
    std::filesystem::create_directories(dir / "cam1");
    cv::FileStorage storage(dir / "cam1/config.xml", cv::FileStorage::WRITE);
    storage << "CameraMatrix" << K << "DistortionCoeffs" << dist << "Rotation" << rvec << "Translation" << tvec
            << "image_width" << 644 << "image_height" << 486;
  }
  const Rig imported = ImportCalibration(CalibFormat::kOpenCvXml, dir.path());
  ASSERT_EQ(imported.size(), 1);
  double worst_px = 0.0;
  for (std::size_t k = 0; k < corners_mm.size(); ++k) {
    const Eigen::Vector3d corner_m(corners_mm[k].x / 1000.0, corners_mm[k].y / 1000.0, corners_mm[k].z / 1000.0);
    worst_px = std::max(worst_px, (imported.cameras[0].Project(corner_m) - Eigen::Vector2d(pixels[k].x, pixels[k].y)).norm());
  }
  EXPECT_LT(worst_px, 1e-4);
  EXPECT_NEAR(imported.cameras[0].center_in_world().z(), -2.0, 1e-4);  // board z points into the floor
  ImportOptions z_up;
  z_up.up_axis = "-z";
  const Rig upright = ImportCalibration(CalibFormat::kOpenCvXml, dir.path(), z_up);
  EXPECT_LT((upright.cameras[0].center_in_world() - Eigen::Vector3d(2.5, -1.0, 2.0)).norm(), 1e-4);
  EXPECT_LT(MaxProjectionDifference(Rig{{camera}}, upright), 1e-4);
}

TEST(OpenCvXmlImportTest, UnknownSizeAndLongDistortionAreErrors) {
  TempDir dir;
  Camera camera = GroundTruthRig(1).cameras[0];
  WriteOpenCvXml(camera, dir / "a/config.xml", false);
  ExpectInputError([&] { ImportCalibration(CalibFormat::kOpenCvXml, dir / "a/config.xml"); }, "image size unknown");
  {
    cv::FileStorage storage(dir / "b.xml", cv::FileStorage::WRITE);
    cv::Mat dist = cv::Mat::zeros(1, 8, CV_64F);
    dist.at<double>(6) = 0.2;
    storage << "CameraMatrix" << cv::Mat::eye(3, 3, CV_64F) << "DistortionCoeffs" << dist << "rvec"
            << cv::Mat::zeros(3, 1, CV_64F) << "tvec" << cv::Mat::zeros(3, 1, CV_64F) << "image_width" << 10
            << "image_height" << 10;
  }
  ExpectInputError([&] { ImportCalibration(CalibFormat::kOpenCvXml, dir / "b.xml"); },
                   "unsupported distortion model with 8 coefficients");
}

// ------------------------------------------------------------------------------------------
// Options

TEST(ImportOptionsTest, RotationToZUpTakesTheAxisToZ) {
  const std::vector<std::pair<std::string, Eigen::Vector3d>> axes = {
      {"+z", Eigen::Vector3d::UnitZ()}, {"-z", -Eigen::Vector3d::UnitZ()}, {"+y", Eigen::Vector3d::UnitY()},
      {"-y", -Eigen::Vector3d::UnitY()}, {"+x", Eigen::Vector3d::UnitX()}, {"-x", -Eigen::Vector3d::UnitX()},
      {"y", Eigen::Vector3d::UnitY()}};
  for (const auto& [name, axis] : axes) {
    const Eigen::Matrix3d rotation = RotationToZUp(name);
    EXPECT_LT((rotation * axis - Eigen::Vector3d::UnitZ()).norm(), 1e-15) << name;
    EXPECT_NEAR(rotation.determinant(), 1.0, 1e-15) << name;
    EXPECT_LT((rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-15) << name;
  }
  EXPECT_THROW(RotationToZUp("up"), UsageError);
}

TEST(ImportOptionsTest, ParseCalibFormat) {
  EXPECT_EQ(ParseCalibFormat("colmap"), CalibFormat::kColmap);
  EXPECT_EQ(ParseCalibFormat("transforms"), CalibFormat::kTransformsJson);
  EXPECT_EQ(ParseCalibFormat("qualisys"), CalibFormat::kQualisys);
  EXPECT_EQ(ParseCalibFormat("plain"), CalibFormat::kPlainText);
  EXPECT_EQ(ParseCalibFormat("opencv-xml"), CalibFormat::kOpenCvXml);
  EXPECT_EQ(ParseCalibFormat("easymocap"), CalibFormat::kEasyMocap);
  try {
    ParseCalibFormat("vicon");
    ADD_FAILURE() << "expected UsageError";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("opencv-xml"), std::string::npos) << error.what();
  }
}

// ------------------------------------------------------------------------------------------
// Real files from ../shared/data: plausibility.

// The point nearest (least squares) to all optical axes, and the largest axis distance to it.
double AxesConvergence(const Rig& rig, Eigen::Vector3d* point) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& camera : rig.cameras) {
    const Eigen::Vector3d d = camera.optical_axis_in_world();
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += P;
    b += P * camera.center_in_world();
  }
  *point = A.ldlt().solve(b);
  double worst = 0.0;
  for (const auto& camera : rig.cameras) {
    const Eigen::Vector3d d = camera.optical_axis_in_world();
    const Eigen::Vector3d to_point = *point - camera.center_in_world();
    EXPECT_GT(to_point.dot(d), 0.0) << camera.name << " looks away from the common point";
    worst = std::max(worst, (to_point - to_point.dot(d) * d).norm());
  }
  return worst;
}

// Checks that the cameras look at a common point, from 1 to 15 m away, with plausible focals.
void ExpectPlausibleRig(const Rig& rig, const std::string& label) {
  Eigen::Vector3d point;
  const double worst = AxesConvergence(rig, &point);
  double nearest = 1e9, farthest = 0.0;
  for (const auto& camera : rig.cameras) {
    const double distance = (camera.center_in_world() - point).norm();
    nearest = std::min(nearest, distance);
    farthest = std::max(farthest, distance);
    EXPECT_GT(camera.horizontal_fov_deg(), 20.0) << camera.name;
    EXPECT_LT(camera.horizontal_fov_deg(), 120.0) << camera.name;
  }
  std::cout << label << ": " << rig.size() << " cameras, axes within " << worst << " m of (" << point.transpose()
            << "), camera distances " << nearest << " to " << farthest << " m, fx " << rig.cameras[0].K(0, 0)
            << " px, hfov " << rig.cameras[0].horizontal_fov_deg() << " deg\n";
  EXPECT_LT(worst, 1.5);
  EXPECT_GT(nearest, 1.0);
  EXPECT_LT(farthest, 15.0);
}

TEST(RealImportTest, QualisysPose2Sim) {
  const std::string path = SharedDataPath("real/pose2sim_single/calibration/Calib.qca.txt");
  if (path.empty()) GTEST_SKIP() << "shared data real/pose2sim_single not present";
  const Rig rig = ImportCalibration(CalibFormat::kQualisys, path);
  ASSERT_EQ(rig.names(), (std::vector<std::string>{"cam01", "cam02", "cam03", "cam04"}));
  for (const auto& camera : rig.cameras) {
    EXPECT_EQ(camera.width, 1088);
    EXPECT_EQ(camera.height, 1920);
    EXPECT_NEAR(camera.K(0, 0), 107599.671875 / 64.0, 200.0);
    // Cameras on tripods about 1.7 to 2.1 m above the floor (z up, metres).
    EXPECT_GT(camera.center_in_world().z(), 1.0) << camera.name;
    EXPECT_LT(camera.center_in_world().z(), 3.0) << camera.name;
  }
  ExpectPlausibleRig(rig, "pose2sim Qualisys");
}

TEST(RealImportTest, TsinghuaPlainText) {
  const std::string path = SharedDataPath("real/tsinghua_lkB/CalibParamsB.txt");
  if (path.empty()) GTEST_SKIP() << "shared data real/tsinghua_lkB not present";
  ImportOptions options;
  options.metres_per_unit = 0.1;  // decimetres
  const Rig rig = ImportCalibration(CalibFormat::kPlainText, path, options);
  ASSERT_EQ(rig.size(), 20);
  EXPECT_EQ(rig.cameras[0].name, "cam00");
  EXPECT_EQ(rig.cameras[19].name, "cam19");
  EXPECT_EQ(rig.cameras[0].width, 1024);
  EXPECT_EQ(rig.cameras[0].height, 768);
  EXPECT_LT(rig.cameras[0].center_in_world().norm(), 1e-9);  // camera 0 is the world frame
  ExpectPlausibleRig(rig, "tsinghua plain");
}

TEST(RealImportTest, UtrechtOpenCvXml) {
  const std::string path = SharedDataPath("real/utrecht_4cam");
  if (path.empty()) GTEST_SKIP() << "shared data real/utrecht_4cam not present";
  const Rig rig = ImportCalibration(CalibFormat::kOpenCvXml, path);
  ASSERT_EQ(rig.names(), (std::vector<std::string>{"cam1", "cam2", "cam3", "cam4"}));
  for (const auto& camera : rig.cameras) {
    EXPECT_EQ(camera.width, 644);  // from the videos beside config.xml
    EXPECT_EQ(camera.height, 486);
  }
  ExpectPlausibleRig(rig, "utrecht OpenCV XML");
}

}  // namespace
}  // namespace confluent
