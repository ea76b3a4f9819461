// correspondences.json I/O, validation and the automatic augmentation (report section 4.2).

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "deform/correspondences.h"
#include "tests/deform/test_geometry.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(Correspondences, RoundTrip) {
  testing::TempDir dir;
  Correspondences c;
  c.scan_path = "scan.ply";
  c.pairs.push_back({812, 40211, "left_forearm", 1.0});
  c.pairs.push_back({3, 5, "", 2.5});
  WriteCorrespondences(dir / "c.json", c);
  const Correspondences back = ReadCorrespondences(dir / "c.json");
  ASSERT_EQ(back.pairs.size(), 2u);
  EXPECT_EQ(back.scan_path, "scan.ply");
  EXPECT_EQ(back.pairs[0].template_triangle, 812);
  EXPECT_EQ(back.pairs[0].scan_triangle, 40211);
  EXPECT_EQ(back.pairs[0].segment, "left_forearm");
  EXPECT_EQ(back.pairs[1].segment, "");
  EXPECT_DOUBLE_EQ(back.pairs[1].weight, 2.5);
  EXPECT_EQ(SegmentsWithoutPairs(back, {"left_forearm", "head"}), std::vector<std::string>{"head"});
}

TEST(Correspondences, BadFilesNameTheFileAndThePair) {
  testing::TempDir dir;
  const std::string path = dir / "bad.json";
  auto expect_error = [&](const std::string& text, const std::string& needle) {
    WriteText(path, text);
    try {
      ReadCorrespondences(path);
      ADD_FAILURE() << "no error for " << text;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find(needle), std::string::npos) << error.what();
    }
  };
  expect_error("{\"pairs\": [", "invalid JSON");
  expect_error("{\"pears\": []}", "\"pairs\"");
  expect_error("{\"pairs\": [{\"template_triangle\": 1}]}", "scan_triangle");
  expect_error("{\"pairs\": [{\"template_triangle\": 1, \"scan_triangle\": -4}]}", "out of range");
  expect_error("{\"pairs\": [{\"template_triangle\": 1.5, \"scan_triangle\": 4}]}", "integer");
  expect_error("{\"pairs\": [{\"template_triangle\": 1, \"scan_triangle\": 4, \"weight\": 0}]}", "weight");
  EXPECT_THROW(ReadCorrespondences(dir / "missing.json"), InputError);
}

TEST(Correspondences, ValidationNamesSourceAndPair) {
  Correspondences c;
  c.pairs.push_back({1, 2, "", 1.0});
  c.pairs.push_back({7, 50, "", 1.0});
  try {
    ValidateCorrespondences(c, 10, 20, "my.json");
    FAIL();
  } catch (const InputError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("my.json"), std::string::npos) << what;
    EXPECT_NE(what.find("pair 1"), std::string::npos) << what;
    EXPECT_NE(what.find("scan triangle out of range"), std::string::npos) << what;
  }
  c.pairs[1] = {1, 2, "", 1.0};
  EXPECT_THROW(ValidateCorrespondences(c, 10, 20, "my.json"), InputError);  // repeated pair
  c.pairs[1] = {3, 2, "", 1.0};
  EXPECT_THROW(ValidateCorrespondences(c, 10, 20, "my.json"), InputError);  // scan triangle used twice
  c.pairs[1] = {3, 4, "", 1.0};
  EXPECT_NO_THROW(ValidateCorrespondences(c, 10, 20, "my.json"));
  EXPECT_THROW(ValidateCorrespondences(Correspondences{}, 10, 20, "my.json"), InputError);
}

TEST(Correspondences, AugmentationCastsMatchingDirections) {
  // Template: coarse tube; scan: finer tube, thicker, rotated tessellation. One given pair per
  // "part" at 4 heights; 8 directions give 7 new pairs each, at matching angles.
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 16);
  const Mesh scan = testing::MakeTube(0.045, 0.6, 60, 40, 0.1);
  const Correspondences given = testing::TubePairs(template_mesh, scan, {0.1, 0.2, 0.4, 0.5}, 1, 0.04, 0.3);
  const Correspondences augmented = AugmentCorrespondences(template_mesh, scan, given);
  ASSERT_EQ(augmented.pairs.size(), 4u * 8u);
  for (std::size_t k = 0; k < augmented.pairs.size(); ++k) {
    const CorrespondencePair& pair = augmented.pairs[k];
    const Eigen::Vector3d a = testing::FaceCentroid(template_mesh, pair.template_triangle);
    const Eigen::Vector3d b = testing::FaceCentroid(scan, pair.scan_triangle);
    // Same angle around the axis (within the coarse template's face size) and same height.
    const double angle = std::abs(std::remainder(std::atan2(a.y(), a.x()) - std::atan2(b.y(), b.x()), 2 * M_PI));
    EXPECT_LT(angle, 2 * M_PI / 16) << "pair " << k;
    EXPECT_NEAR(a.z(), b.z(), 0.025) << "pair " << k;
    EXPECT_EQ(pair.segment, given.pairs[k < 4 ? k : (k - 4) / 7].segment);
  }
  ValidateCorrespondences(augmented, template_mesh.num_faces(), scan.num_faces(), "augmented");
}

}  // namespace
}  // namespace confluent
