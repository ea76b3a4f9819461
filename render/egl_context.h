#pragma once
// A headless OpenGL 4.x core-profile context through EGL: a GPU's EGL device when there is one,
// else Mesa's surfaceless platform (llvmpipe, software). No window system is touched.

#include <memory>
#include <string>

#include "core/error.h"

namespace confluent {

// An OpenGL context could not be created (no EGL, no usable platform or device, GL version
// too old). what() says which step failed, the EGL error code name, and how to fix it.
class RenderContextError : public Error {
 public:
  using Error::Error;
};

// Which EGL platform to open.
enum class EglPlatform {
  kAuto,         // $CONFLUENT_EGL when set (auto|device|device:N|surfaceless), else automatic:
                 // the first GPU EGL device that works, else surfaceless
  kDevice,       // a GPU EGL device (EGL_EXT_platform_device); fails when there is none
  kSurfaceless,  // Mesa's surfaceless platform (EGL_MESA_platform_surfaceless, llvmpipe)
};

// Options for EglContext.
struct EglContextOptions {
  EglPlatform platform = EglPlatform::kAuto;
  int device_index = -1;  // with kDevice: index into eglQueryDevicesEXT; -1 = first GPU device
  int gl_major_version = 4;  // minimum OpenGL core-profile version requested
  int gl_minor_version = 3;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// What EglContext opened; for diagnostics (`confluent render-info`).
struct EglContextInfo {
  std::string platform;     // "device" or "surfaceless"
  std::string device;       // e.g. "EGL device 0 (/dev/dri/renderD128)"; empty for surfaceless
  std::string egl_vendor;   // EGL_VENDOR
  std::string egl_version;  // EGL_VERSION
  std::string gl_vendor;    // GL_VENDOR
  std::string gl_renderer;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string gl_version;   // GL_VERSION
  std::string glsl_version; // GL_SHADING_LANGUAGE_VERSION
  bool software = false;    // true for llvmpipe/softpipe/swrast
};

// Owns one headless EGL context (no surface; render into framebuffer objects). The context is
// made current on the constructing thread. The EGLDisplay is process-wide, so it is left
// initialised on destruction (terminating it would break other contexts on the same display);
// only this object's context is destroyed. Not copyable; movable.
class EglContext {
 public:
  // Creates the context. Throws RenderContextError when no context can be created or
  // $CONFLUENT_EGL has an unknown value, and UsageError for bad options.
  explicit EglContext(const EglContextOptions& options = {});
  ~EglContext();
  EglContext(EglContext&&) noexcept;
  EglContext& operator=(EglContext&&) noexcept;
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // Makes this context current on the calling thread (cheap when it already is).
  void MakeCurrent() const;
  const EglContextInfo& info() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
