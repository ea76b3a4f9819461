// PC2 point cache round trip.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "deform/point_cache.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(PointCache, RoundTripAndHeader) {
  testing::TempDir dir;
  std::vector<RowMatrixX3d> frames;
  {
    PointCacheWriter writer(dir / "a.pc2", 5);
    for (int f = 0; f < 3; ++f) {
      frames.push_back(RowMatrixX3d::Random(5, 3));
      writer.Append(frames.back());
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "a.pc2"));  // only renamed by Finish()
    writer.Finish();
  }
  EXPECT_EQ(std::filesystem::file_size(dir / "a.pc2"), 32u + 3 * 5 * 3 * 4);
  const auto back = ReadPointCache(dir / "a.pc2");
  ASSERT_EQ(back.size(), 3u);
  for (int f = 0; f < 3; ++f) EXPECT_LT((back[f] - frames[f]).cwiseAbs().maxCoeff(), 1e-6);
  {
    PointCacheWriter abandoned(dir / "b.pc2", 5);
    abandoned.Append(frames[0]);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "b.pc2"));
  EXPECT_FALSE(std::filesystem::exists(dir / "b.pc2.tmp"));
  std::ofstream(dir / "bad.pc2") << "POINTCACHE2";
  EXPECT_THROW(ReadPointCache(dir / "bad.pc2"), InputError);
}

}  // namespace
}  // namespace confluent
