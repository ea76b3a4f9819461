// `confluent demo`, the README's main command, end to end on the tiny studio preset.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

TEST(DemoCommand, TinyPresetRunsThePipelineAndReports) {
  testing::TempDir out;
  const testing::CommandResult first =
      testing::RunConfluent({"demo", "--preset", "tiny", "--out", out.path(), "--evaluate-every", "2"});
  ASSERT_EQ(first.exit_code, 0) << first.stdout_text << first.stderr_text;
  for (const char* file : {"capture/intri.yml", "capture_gt/synth.json", "check/cam00.png", "run/run.json",
                           "run/poses.json", "run/scan/000009.ply", "run/metrics.json", "run/report.html"})
    EXPECT_TRUE(fs::exists(fs::path(out.path()) / file)) << file;
  EXPECT_NE(first.stdout_text.find("held-out evaluation"), std::string::npos) << first.stdout_text;
  EXPECT_NE(first.stdout_text.find("report:"), std::string::npos);
  const nlohmann::json metrics = nlohmann::json::parse(std::ifstream(fs::path(out.path()) / "run/metrics.json"));
  EXPECT_EQ(metrics["rows"].size(), 10u);  // 5 scored frames x 2 held-out cameras
  EXPECT_GT(metrics["scan"]["iou_mean"].get<double>(), 0.6);
  // A second demo reuses the capture and the finished run.
  const testing::CommandResult second =
      testing::RunConfluent({"demo", "--preset", "tiny", "--out", out.path(), "--evaluate-every", "2"});
  ASSERT_EQ(second.exit_code, 0) << second.stderr_text;
  EXPECT_NE(second.stdout_text.find("reusing the capture"), std::string::npos);
  EXPECT_NE(second.stdout_text.find("0 computed"), std::string::npos);
}

}  // namespace
}  // namespace confluent
