// Tests of the EasyMocap intri.yml / extri.yml reader and writer.

#include "calib/easymocap_io.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::TempDir;
using testing::WriteFile;

Rig ExampleRig() {
  Rig rig;
  const char* names[] = {"01", "cam_b", "side-3"};
  for (int i = 0; i < 3; ++i) {
    Camera camera;
    camera.name = names[i];
    camera.width = 640 + 2 * i;
    camera.height = 480 + i;
    camera.K << 600.123456789 + i, 0.25 * i, 320.5, 0, 601.987654321, 240.25 - i, 0, 0, 1;
    camera.dist << -0.21 + 0.01 * i, 0.0734, 1.5e-4, -2.25e-4, i == 1 ? 0.0 : -0.0123;
    camera.rotation = Eigen::AngleAxisd(0.3 + 1.1 * i, Eigen::Vector3d(0.2, -0.5 + i, 1.0).normalized())
                          .toRotationMatrix();
    camera.translation = Eigen::Vector3d(0.1 * i, -1.7, 3.3 + 0.123456789 * i);
    rig.cameras.push_back(camera);
  }
  return rig;
}

// An intri.yml for camera "a" with the given K and dist data lists.
std::string Intri(const std::string& k_data, const std::string& dist_data, int dist_cols = 5) {
  return "%YAML:1.0\n---\nnames:\n  - \"a\"\n"
         "K_a: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [" +
         k_data +
         "]\n"
         "dist_a: !!opencv-matrix\n   rows: 1\n   cols: " +
         std::to_string(dist_cols) + "\n   dt: d\n   data: [" + dist_data + "]\nH_a: 480\nW_a: 640\n";
}

std::string Extri(const std::string& rot_data, bool use_rodrigues = false) {
  const std::string rotation = use_rodrigues
                                   ? "R_a: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [" + rot_data + "]\n"
                                   : "Rot_a: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [" + rot_data + "]\n";
  return "%YAML:1.0\n---\nnames:\n  - \"a\"\n" + rotation +
         "T_a: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [0.1, 0.2, 3.0]\n";
}

const char kGoodK[] = "500., 0., 319.5, 0., 500., 239.5, 0., 0., 1.";
const char kGoodDist[] = "-0.1, 0.01, 0.0, 0.0, 0.0";
const char kIdentity[] = "1, 0, 0, 0, 1, 0, 0, 0, 1";

// Reads the pair and expects an InputError whose message contains every one of `parts`.
void ExpectReadError(const TempDir& dir, const std::vector<std::string>& parts) {
  try {
    ReadEasyMocap(dir / "intri.yml", dir / "extri.yml");
    ADD_FAILURE() << "no error; expected " << parts.front();
  } catch (const InputError& error) {
    const std::string message = error.what();
    for (const auto& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
  }
}

TEST(EasyMocapIoTest, RoundTripIsExact) {
  TempDir dir;
  const Rig rig = ExampleRig();
  WriteEasyMocap(rig, dir.path());
  const Rig read = ReadEasyMocap(dir / "intri.yml", dir / "extri.yml");
  ASSERT_EQ(read.names(), rig.names());
  for (int i = 0; i < rig.size(); ++i) {
    const Camera& a = rig.cameras[i];
    const Camera& b = read.cameras[i];
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.K, b.K);
    EXPECT_EQ(a.dist, b.dist);
    EXPECT_EQ(a.rotation, b.rotation);
    EXPECT_EQ(a.translation, b.translation);
  }
  // Writing the read rig again gives identical files.
  TempDir again;
  WriteEasyMocap(read, again.path());
  EXPECT_EQ(ReadTextFile(dir / "intri.yml"), ReadTextFile(again / "intri.yml"));
}

TEST(EasyMocapIoTest, RodriguesOnlyExtrinsics) {
  TempDir dir;
  const Eigen::Vector3d rodrigues(0.3, -1.2, 0.4);
  WriteFile(dir / "intri.yml", Intri(kGoodK, kGoodDist));
  WriteFile(dir / "extri.yml", Extri("0.3, -1.2, 0.4", true));
  const Rig rig = ReadEasyMocap(dir / "intri.yml", dir / "extri.yml");
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(rodrigues.norm(), rodrigues.normalized()).toRotationMatrix();
  EXPECT_LT((rig.cameras[0].rotation - expected).norm(), 1e-14);
  EXPECT_EQ(rig.cameras[0].translation, Eigen::Vector3d(0.1, 0.2, 3.0));
  EXPECT_EQ(rig.cameras[0].K(0, 2), 319.5);
  EXPECT_EQ(rig.cameras[0].width, 640);
  EXPECT_EQ(rig.cameras[0].height, 480);
}

TEST(EasyMocapIoTest, ShortAndLongDistortionVectors) {
  TempDir dir;
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  // Four coefficients k1 k2 p1 p2: k3 = 0.
  WriteFile(dir / "intri.yml", Intri(kGoodK, "-0.1, 0.02, 0.001, 0.002", 4));
  Rig rig = ReadEasyMocap(dir / "intri.yml", dir / "extri.yml");
  Vector5d expected;
  expected << -0.1, 0.02, 0.001, 0.002, 0.0;
  EXPECT_EQ(rig.cameras[0].dist, expected);
  // Eight coefficients with zero rational terms are the same model.
  WriteFile(dir / "intri.yml", Intri(kGoodK, "-0.1, 0.02, 0.001, 0.002, 0.0, 0.0, 0.0, 0.0", 8));
  rig = ReadEasyMocap(dir / "intri.yml", dir / "extri.yml");
  EXPECT_EQ(rig.cameras[0].dist, expected);
  // Non-zero rational terms cannot be represented.
  WriteFile(dir / "intri.yml", Intri(kGoodK, "-0.1, 0.02, 0.001, 0.002, 0.0, 0.3, 0.0, 0.0", 8));
  ExpectReadError(dir, {"intri.yml", "camera a", "unsupported distortion model with 8 coefficients"});
  WriteFile(dir / "intri.yml", Intri(kGoodK, "-0.1, 0.02, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.5", 14));
  ExpectReadError(dir, {"intri.yml", "unsupported distortion model with 14 coefficients"});
}

TEST(EasyMocapIoTest, NanInKIsAnError) {
  TempDir dir;
  WriteFile(dir / "intri.yml", Intri("500., 0., 319.5, 0., .nan, 239.5, 0., 0., 1.", kGoodDist));
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml", "camera a", "K_a", "NaN"});
}

TEST(EasyMocapIoTest, NonNumericEntryIsAnError) {
  TempDir dir;
  WriteFile(dir / "intri.yml", Intri("500., 0., 319.5, 0., five, 239.5, 0., 0., 1.", kGoodDist));
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml", "camera a", "K_a", "numeric", "five"});
  // A non-numeric scalar.
  std::string text = Intri(kGoodK, kGoodDist);
  text.replace(text.find("W_a: 640"), 8, "W_a: wide");
  WriteFile(dir / "intri.yml", text);
  ExpectReadError(dir, {"intri.yml", "camera a", "W_a", "numeric"});
}

TEST(EasyMocapIoTest, CameraWithoutKIsAnError) {
  TempDir dir;
  std::string text = Intri(kGoodK, kGoodDist);
  text.replace(text.find("  - \"a\"\n"), 8, "  - \"a\"\n  - \"b\"\n");
  WriteFile(dir / "intri.yml", text);
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml", "camera b", "missing K_b"});
}

TEST(EasyMocapIoTest, WrongShapeIsAnError) {
  TempDir dir;
  std::string text = Intri("500., 0., 319.5, 0., 500., 239.5", kGoodDist);
  text.replace(text.find("rows: 3"), 7, "rows: 2");
  WriteFile(dir / "intri.yml", text);
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {"intri.yml", "camera a", "K_a must be 3x3, got 2x3"});
}

TEST(EasyMocapIoTest, NonRotationIsAnError) {
  TempDir dir;
  WriteFile(dir / "intri.yml", Intri(kGoodK, kGoodDist));
  WriteFile(dir / "extri.yml", Extri("1, 0, 0, 0, 1, 0, 0, 0, 2"));
  ExpectReadError(dir, {dir / "extri.yml", "camera a", "Rot_a", "not a rotation"});
  WriteFile(dir / "extri.yml", Extri("1, 0, 0, 0, 1, 0, 0, 0, -1"));  // a reflection
  ExpectReadError(dir, {dir / "extri.yml", "not a rotation"});
}

TEST(EasyMocapIoTest, ZeroFocalIsAnError) {
  TempDir dir;
  WriteFile(dir / "intri.yml", Intri("0., 0., 319.5, 0., 500., 239.5, 0., 0., 1.", kGoodDist));
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {"intri.yml", "camera a", "focal length"});
}

TEST(EasyMocapIoTest, MalformedOrMissingFilesAreInputErrors) {
  TempDir dir;
  WriteFile(dir / "intri.yml", "%YAML:1.0\n---\nnames: [a\nK_a: : :\n");
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml"});
  WriteFile(dir / "intri.yml", Intri(kGoodK, kGoodDist));
  std::remove((dir / "extri.yml").c_str());
  ExpectReadError(dir, {dir / "extri.yml", "not found"});
  WriteFile(dir / "extri.yml", "%YAML:1.0\n---\nnames:\n  - \"a\"\n");
  ExpectReadError(dir, {dir / "extri.yml", "camera a", "missing Rot_a or R_a"});
}

// OpenCV 4.6's YAML parser never returns from a nested map entry without a name (found by
// fuzzing); the reader refuses it, naming the file, before OpenCV sees it.
TEST(EasyMocapIoTest, EntryWithoutANameIsRefusedNotParsedForEver) {
  TempDir dir;
  WriteFile(dir / "intri.yml", "%YAML:1.0\nK_a: !!opencv-matrix\n   rows: 3\n  : 1\n");
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml", "entry without a name"});
}

// OpenCV's parser also loops for ever on this one (found by fuzz_easymocap); "---" with text
// after it on its line is refused first, and a well-formed file with "---" alone still reads.
TEST(EasyMocapIoTest, DocumentMarkerWithTextIsRefusedNotParsedForEver) {
  TempDir dir;
  WriteFile(dir / "intri.yml", "%YAML:1.0\n---n:a\nmse\n - x\n");
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml", "document marker"});
  WriteEasyMocap(ExampleRig(), dir.path());
  const std::string intri = ReadTextFile(dir / "intri.yml");
  ASSERT_NE(intri.find("\n---\n"), std::string::npos) << "OpenCV writes the marker alone on its line";
  EXPECT_EQ(ReadEasyMocap(dir / "intri.yml", dir / "extri.yml").size(), ExampleRig().size());
}

// A file on which OpenCV's parser loops for ever with none of the patterns above (found by
// fuzz_easymocap) is refused after the child process that tries it first runs out of time.
TEST(EasyMocapIoTest, FileTheParserNeverFinishesIsRefusedInTime) {
  TempDir dir;
  WriteFile(dir / "intri.yml",
            "%YAML:1.s: \xb3\n   dt: d\n ncv-matrix\n   rows: 5\n   cols: 3\n   dt: d\n   data:4s: 5\n"
            "   cols: 3\n   dt: d\n   data:40\n");
  WriteFile(dir / "extri.yml", Extri(kIdentity));
  ExpectReadError(dir, {dir / "intri.yml", "did not finish"});
}

TEST(EasyMocapIoTest, UnwritableNameIsAnOutputError) {
  TempDir dir;
  Rig rig = ExampleRig();
  rig.cameras[1].name = "bad name";
  EXPECT_THROW(WriteEasyMocap(rig, dir.path()), OutputError);
}

}  // namespace
}  // namespace confluent
