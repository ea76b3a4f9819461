// `confluent render-info`: the EGL probe command, and its error for an unusable platform.

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(RenderInfoCommand, DescribesTheContextAndPassesTheSelfTest) {
  const testing::CommandResult result = testing::RunConfluent({"render-info"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_NE(result.stdout_text.find("GL renderer"), std::string::npos) << result.stdout_text;
  EXPECT_NE(result.stdout_text.find("self-test     ok"), std::string::npos) << result.stdout_text;
}

TEST(RenderInfoCommand, UnusablePlatformIsAOneLineError) {
  const char* old = std::getenv("CONFLUENT_EGL");
  const std::string saved = old == nullptr ? "" : old;
  setenv("CONFLUENT_EGL", "wayland", 1);
  const testing::CommandResult result = testing::RunConfluent({"render-info"});
  if (old == nullptr)
    unsetenv("CONFLUENT_EGL");
  else
    setenv("CONFLUENT_EGL", saved.c_str(), 1);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("confluent render-info: error: CONFLUENT_EGL='wayland'"), std::string::npos)
      << result.stderr_text;
  // A missing EGL device: also a clear error, never a crash.
  const testing::CommandResult missing = testing::RunConfluent({"render-info", "--device", "42"});
  EXPECT_EQ(missing.exit_code, 1) << missing.stdout_text;
  EXPECT_NE(missing.stderr_text.find("no EGL device 42"), std::string::npos) << missing.stderr_text;
}

}  // namespace
}  // namespace confluent
