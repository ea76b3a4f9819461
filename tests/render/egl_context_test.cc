// EglContext: opening a headless context, its description, two at once, and clear errors for
// a wrong platform, a missing device or an impossible GL version.
#include "render/egl_context.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "render/renderer.h"
#include "tests/render/renderer_test_util.h"

namespace confluent {
namespace {

using render_test::MakeIcosphere;
using render_test::TestCamera;
// Sets an environment variable for the lifetime of the object.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    const char* old = std::getenv(name);
    had_old_ = old != nullptr;
    if (had_old_) old_ = old;
    setenv(name, value, 1);
  }
  ~ScopedEnv() {
    if (had_old_)
      setenv(name_.c_str(), old_.c_str(), 1);
    else
      unsetenv(name_.c_str());
  }

 private:
  std::string name_, old_;
  bool had_old_ = false;
};

TEST(EglContext, OpensAndDescribesItself) {
  EglContext context;
  const EglContextInfo& info = context.info();
  EXPECT_TRUE(info.platform == "device" || info.platform == "surfaceless") << info.platform;
  EXPECT_FALSE(info.gl_renderer.empty());
  EXPECT_EQ(info.gl_version.rfind("4.", 0), 0u) << info.gl_version;
  RecordProperty("gl_renderer", info.gl_renderer);
}

TEST(EglContext, SurfacelessPlatformWorks) {
  EglContextOptions options;
  options.platform = EglPlatform::kSurfaceless;
  EglContext context(options);
  EXPECT_EQ(context.info().platform, "surfaceless");
  EXPECT_TRUE(context.info().software) << context.info().gl_renderer;
}

TEST(EglContext, TwoContextsCoexist) {
  MeshRenderer first;
  first.AddMesh(MakeIcosphere(Eigen::Vector3d::Zero(), 0.5, 2));
  {
    MeshRenderer second;
    second.AddMesh(MakeIcosphere(Eigen::Vector3d::Zero(), 0.2, 2));
    second.Render(TestCamera(false));
  }
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  const RenderResult result = first.Render(TestCamera(false), request);
  int area = 0;
  for (std::uint8_t value : result.silhouette.data) area += value != 0;
  EXPECT_GT(area, 1000);
}

TEST(EglContextBadInput, UnknownPlatformInEnvironmentIsAClearError) {
  ScopedEnv env("CONFLUENT_EGL", "x11-please");
  try {
    MeshRenderer renderer;
    FAIL() << "expected RenderContextError";
  } catch (const RenderContextError& error) {
    EXPECT_NE(std::string(error.what()).find("CONFLUENT_EGL='x11-please'"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("surfaceless"), std::string::npos) << error.what();
  }
}

TEST(EglContextBadInput, MissingDeviceIsAClearError) {
  ScopedEnv env("CONFLUENT_EGL", "device:99");
  try {
    EglContext context;
    FAIL() << "expected RenderContextError";
  } catch (const RenderContextError& error) {
    EXPECT_NE(std::string(error.what()).find("no EGL device 99"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("libegl-mesa0"), std::string::npos) << error.what();
  }
}

TEST(EglContextBadInput, ImpossibleGlVersionIsAClearError) {
  EglContextOptions options;
  options.platform = EglPlatform::kSurfaceless;
  options.gl_major_version = 9;
  options.gl_minor_version = 9;
  try {
    EglContext context(options);
    FAIL() << "expected RenderContextError";
  } catch (const RenderContextError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("9.9"), std::string::npos) << message;
    EXPECT_NE(message.find("EGL_"), std::string::npos) << "names the EGL error code: " << message;
  }
  // A later context still works.
  EXPECT_NO_THROW(EglContext());
}

}  // namespace
}  // namespace confluent
