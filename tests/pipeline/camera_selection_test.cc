#include "pipeline/camera_selection.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace confluent {
namespace {

Rig NamedRig(const std::vector<std::string>& names) {
  Rig rig;
  for (const std::string& name : names) {
    Camera camera;
    camera.name = name;
    rig.cameras.push_back(camera);
  }
  return rig;
}

TEST(CameraSelection, HeldOutCamerasAreNeverUsedAndAreRecordedInOrder) {
  const Rig rig = NamedRig({"cam00", "right", "cam02", "left"});
  const CameraSelection selection(rig, {"right", "left", "right"});
  EXPECT_EQ(selection.num_cameras(), 4);
  EXPECT_EQ(selection.num_used(), 2);
  EXPECT_EQ(selection.used(), (std::vector<int>{0, 2}));
  EXPECT_EQ(selection.held_out(), (std::vector<int>{1, 3}));
  EXPECT_EQ(selection.held_out_names(), (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(selection.held_out_mask(), (std::vector<bool>{false, true, false, true}));
  EXPECT_TRUE(selection.is_used(2));
  EXPECT_TRUE(selection.is_held_out(3));
  const std::vector<Camera> used = selection.UsedCameras(rig);
  ASSERT_EQ(used.size(), 2u);
  EXPECT_EQ(used[0].name, "cam00");
  EXPECT_EQ(used[1].name, "cam02");
  EXPECT_NO_THROW(selection.RequireUsed(2, "--exclude-camera"));
}

TEST(CameraSelection, EveryCameraIsUsedByDefault) {
  const CameraSelection selection(NamedRig({"a", "b", "c"}));
  EXPECT_EQ(selection.used(), (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(selection.held_out().empty());
  EXPECT_TRUE(selection.held_out_names().empty());
}

TEST(CameraSelection, UnknownNameAndTooFewCamerasAreUsageErrorsNamingTheProblem) {
  const Rig rig = NamedRig({"a", "b", "c"});
  try {
    CameraSelection(rig, {"d"});
    FAIL() << "an unknown camera was accepted";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("d"), std::string::npos) << error.what();
  }
  const CameraSelection two_out(rig, {"a", "b"});
  try {
    two_out.RequireUsed(2, "--exclude-camera");
    FAIL() << "one used camera passed a requirement of two";
  } catch (const UsageError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("--exclude-camera"), std::string::npos) << message;
    EXPECT_NE(message.find("1 of 3"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace confluent
