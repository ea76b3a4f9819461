// confluent render-info: open the headless EGL/OpenGL context and describe it.

#include <cstdio>
#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "render/renderer.h"
#include "render/self_test.h"

namespace confluent::app {
namespace {

int RunRenderInfo(const ParsedArgs& args, const Context&) {
  MeshRendererOptions options;
  const std::string platform = args.get("platform", "auto");
  if (platform == "device") {
    options.context.platform = EglPlatform::kDevice;
  } else if (platform == "surfaceless") {
    options.context.platform = EglPlatform::kSurfaceless;
  } else if (platform != "auto") {
    throw UsageError("--platform: expected auto, device or surfaceless, got '" + platform + "'");
  }
  options.context.device_index = args.get_int("device", -1);
  if (args.has("device") && options.context.platform == EglPlatform::kAuto)
    options.context.platform = EglPlatform::kDevice;
  if (options.context.device_index < -1) throw UsageError("--device: must be >= 0");
  MeshRenderer renderer(options);
  const EglContextInfo& info = renderer.context_info();
  std::printf("platform      %s\n", info.platform.c_str());
  if (!info.device.empty()) std::printf("device        %s\n", info.device.c_str());
  std::printf("EGL vendor    %s\n", info.egl_vendor.c_str());
  std::printf("EGL version   %s\n", info.egl_version.c_str());
  std::printf("GL vendor     %s\n", info.gl_vendor.c_str());
  std::printf("GL renderer   %s%s\n", info.gl_renderer.c_str(), info.software ? "  (software)" : "");
  std::printf("GL version    %s\n", info.gl_version.c_str());
  std::printf("GLSL version  %s\n", info.glsl_version.c_str());

  const RenderSelfTest test = RunRenderSelfTest(renderer);
  std::printf("self-test     %s (%d of %d pixels)\n", test.ok ? "ok" : "FAILED", test.covered_px, test.expected_px);
  return test.ok ? 0 : 1;
}

}  // namespace

CommandSpec MakeRenderInfoCommand() {
  CommandSpec spec;
  spec.name = "render-info";
  spec.summary = "open the headless OpenGL context and print its platform, vendor and version";
  spec.usage = "[--platform auto|device|surfaceless] [--device N]";
  spec.description =
      "Creates the offscreen EGL context the renderer uses (a GPU EGL device when there is one, else Mesa's\n"
      "surfaceless llvmpipe), prints what it got and renders a small self-test. The environment variable\n"
      "CONFLUENT_EGL=auto|device|device:N|surfaceless chooses the platform when --platform is not given.\n"
      "EGL_LOG_LEVEL=debug makes Mesa explain a failure.";
  spec.options = {{"platform", "NAME", "auto (default), device or surfaceless"},
                  {"device", "N", "use EGL device N (see the device line)"}};
  spec.run = RunRenderInfo;
  return spec;
}

}  // namespace confluent::app
