#pragma once
// Test helper: two rigs are the same cameras, in the same order, to `tolerance` in every
// parameter (K, distortion, rotation and translation entries; sizes exactly). Header-only, so
// that test_support keeps depending on core alone.

#include <gtest/gtest.h>

#include "calib/camera.h"

namespace confluent::testing {

inline void ExpectSameRig(const Rig& expected, const Rig& actual, double tolerance) {
  ASSERT_EQ(actual.names(), expected.names());
  for (int i = 0; i < expected.size(); ++i) {
    const Camera& a = expected.cameras[i];
    const Camera& b = actual.cameras[i];
    SCOPED_TRACE(a.name);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_LE((a.K - b.K).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LE((a.dist - b.dist).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LE((a.rotation - b.rotation).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LE((a.translation - b.translation).cwiseAbs().maxCoeff(), tolerance);
  }
}

}  // namespace confluent::testing
