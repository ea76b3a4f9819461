// Headless EGL context: GPU EGL device or Mesa surfaceless, OpenGL core profile via libepoxy.

#include "render/egl_context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdlib>
#include <cstring>
#include <sstream>
#include <utility>
#include <vector>

namespace confluent {
namespace {

const char* EglErrorName(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

// "what failed (EGL_BAD_xxx 0x300x)" with the current eglGetError().
std::string EglFailure(const std::string& what) {
  const EGLint code = eglGetError();
  std::ostringstream out;
  out << what << " (" << EglErrorName(code) << ", 0x" << std::hex << code << ")";
  return out.str();
}

bool HasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t length = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += length) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[length] == '\0' || p[length] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

constexpr const char* kHint =
    "; for software rendering install libegl-mesa0 and libgl1-mesa-dri (Mesa EGL + llvmpipe), "
    "or choose the platform with CONFLUENT_EGL=surfaceless|device|device:N "
    "(EGL_LOG_LEVEL=debug shows Mesa's diagnostics)";

struct Choice {
  EglPlatform platform = EglPlatform::kAuto;
  int device_index = -1;
};

// The platform to open: explicit options win, else $CONFLUENT_EGL, else automatic.
Choice ResolveChoice(const EglContextOptions& options) {
  Choice choice{options.platform, options.device_index};
  if (options.platform != EglPlatform::kAuto) return choice;
  const char* env = std::getenv("CONFLUENT_EGL");
  if (env == nullptr || *env == '\0') return choice;
  const std::string value(env);
  if (value == "auto") return choice;
  if (value == "surfaceless") return {EglPlatform::kSurfaceless, -1};
  if (value == "device") return {EglPlatform::kDevice, -1};
  if (value.rfind("device:", 0) == 0) {
    const std::string index = value.substr(7);
    char* end = nullptr;
    const long parsed = std::strtol(index.c_str(), &end, 10);
    if (!index.empty() && end != nullptr && *end == '\0' && parsed >= 0 && parsed < 1000)
      return {EglPlatform::kDevice, static_cast<int>(parsed)};
  }
  throw RenderContextError("CONFLUENT_EGL='" + value +
                           "' is not a known EGL platform; use auto, device, device:N or surfaceless");
}

struct Device {
  EGLDeviceEXT handle = nullptr;
  int index = 0;
  bool gpu = false;
  std::string description;
};

std::vector<Device> ListDevices(std::string* why_none) {
  std::vector<Device> devices;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!HasExtension(client, "EGL_EXT_device_enumeration") && !HasExtension(client, "EGL_EXT_device_base")) {
    *why_none = "EGL has no EGL_EXT_device_enumeration";
    return devices;
  }
  if (!HasExtension(client, "EGL_EXT_platform_device")) {
    *why_none = "EGL has no EGL_EXT_platform_device";
    return devices;
  }
  EGLint count = 0;
  if (!eglQueryDevicesEXT(0, nullptr, &count) || count <= 0) {
    *why_none = count <= 0 ? "eglQueryDevicesEXT found no devices" : EglFailure("eglQueryDevicesEXT failed");
    return devices;
  }
  std::vector<EGLDeviceEXT> handles(count);
  if (!eglQueryDevicesEXT(count, handles.data(), &count)) {
    *why_none = EglFailure("eglQueryDevicesEXT failed");
    return devices;
  }
  for (int i = 0; i < count; ++i) {
    Device device;
    device.handle = handles[i];
    device.index = i;
    const char* extensions = eglQueryDeviceStringEXT(handles[i], EGL_EXTENSIONS);
    const bool software = HasExtension(extensions, "EGL_MESA_device_software");
    const bool drm = HasExtension(extensions, "EGL_EXT_device_drm");
    const bool cuda = HasExtension(extensions, "EGL_NV_device_cuda");
    device.gpu = !software && (drm || cuda);
    std::string node;
    if (drm) {
      const char* file = eglQueryDeviceStringEXT(handles[i], EGL_DRM_DEVICE_FILE_EXT);
      if (file != nullptr) node = file;
    }
    device.description = "EGL device " + std::to_string(i) +
                         (software ? " (software)" : node.empty() ? (cuda ? " (CUDA)" : "") : " (" + node + ")");
    devices.push_back(device);
  }
  return devices;
}

}  // namespace

void EglContextOptions::Check() const {
  RequireOption(device_index >= -1, "EglContextOptions.device_index", device_index, ">= -1 (-1 = first GPU device)");
  RequireOption(gl_major_version >= 1, "EglContextOptions.gl_major_version", gl_major_version, ">= 1");
  RequireOption(gl_minor_version >= 0, "EglContextOptions.gl_minor_version", gl_minor_version, ">= 0");
}

struct EglContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EglContextInfo info;

  ~Impl() {
    if (context == EGL_NO_CONTEXT) return;
    if (eglGetCurrentContext() == context) eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, context);
    // The display is deliberately not terminated (process-wide; see the header).
  }

  // Initialises `candidate` and creates a current core context on it. Returns "" on success,
  // else why it failed.
  std::string TryDisplay(EGLDisplay candidate, const EglContextOptions& options) {
    if (candidate == EGL_NO_DISPLAY) return EglFailure("eglGetPlatformDisplayEXT returned no display");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(candidate, &major, &minor)) return EglFailure("eglInitialize failed");
    const char* extensions = eglQueryString(candidate, EGL_EXTENSIONS);
    if (!HasExtension(extensions, "EGL_KHR_surfaceless_context"))
      return "the EGL display lacks EGL_KHR_surfaceless_context";
    if (!eglBindAPI(EGL_OPENGL_API)) return EglFailure("eglBindAPI(EGL_OPENGL_API) failed");

    EGLConfig config = nullptr;
    EGLint num_configs = 0;
    const EGLint pbuffer_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                      EGL_NONE};
    const EGLint any_attribs[] = {EGL_SURFACE_TYPE, EGL_DONT_CARE, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    if (!eglChooseConfig(candidate, pbuffer_attribs, &config, 1, &num_configs) || num_configs == 0) {
      if (!eglChooseConfig(candidate, any_attribs, &config, 1, &num_configs) || num_configs == 0) {
        if (!HasExtension(extensions, "EGL_KHR_no_config_context"))
          return EglFailure("eglChooseConfig found no OpenGL-renderable config");
        config = EGL_NO_CONFIG_KHR;
      }
    }
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, options.gl_major_version,
                                      EGL_CONTEXT_MINOR_VERSION, options.gl_minor_version,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
    EGLContext created = eglCreateContext(candidate, config, EGL_NO_CONTEXT, context_attribs);
    if (created == EGL_NO_CONTEXT) {
      std::ostringstream what;
      what << "eglCreateContext failed for an OpenGL " << options.gl_major_version << "."
           << options.gl_minor_version << " core profile";
      return EglFailure(what.str());
    }
    if (!eglMakeCurrent(candidate, EGL_NO_SURFACE, EGL_NO_SURFACE, created)) {
      const std::string why = EglFailure("eglMakeCurrent (surfaceless) failed");
      eglDestroyContext(candidate, created);
      return why;
    }
    const int version = epoxy_gl_version();
    if (version < options.gl_major_version * 10 + options.gl_minor_version) {
      eglMakeCurrent(candidate, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(candidate, created);
      std::ostringstream what;
      what << "the context has OpenGL " << version / 10 << "." << version % 10 << ", need "
           << options.gl_major_version << "." << options.gl_minor_version;
      return what.str();
    }
    display = candidate;
    context = created;
    auto gl_string = [](GLenum name) {
      const GLubyte* value = glGetString(name);
      return value == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(value));
    };
    auto egl_string = [&](EGLint name) {
      const char* value = eglQueryString(candidate, name);
      return value == nullptr ? std::string() : std::string(value);
    };
    info.egl_vendor = egl_string(EGL_VENDOR);
    info.egl_version = egl_string(EGL_VERSION);
    info.gl_vendor = gl_string(GL_VENDOR);
    info.gl_renderer = gl_string(GL_RENDERER);
    info.gl_version = gl_string(GL_VERSION);
    info.glsl_version = gl_string(GL_SHADING_LANGUAGE_VERSION);
    for (const char* software : {"llvmpipe", "softpipe", "swrast", "SWR"})
      if (info.gl_renderer.find(software) != std::string::npos) info.software = true;
    return "";
  }
};

EglContext::EglContext(const EglContextOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Check();
  const Choice choice = ResolveChoice(options);
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client == nullptr)
    throw RenderContextError(EglFailure("EGL: no client extensions (EGL_EXT_client_extensions missing)") + kHint);
  if (!HasExtension(client, "EGL_EXT_platform_base"))
    throw RenderContextError("EGL: EGL_EXT_platform_base is missing, cannot open a headless display" +
                             std::string(kHint));
  std::vector<std::string> failures;

  if (choice.platform != EglPlatform::kSurfaceless) {
    std::string why_none;
    const std::vector<Device> devices = ListDevices(&why_none);
    if (choice.device_index >= 0 && choice.device_index >= static_cast<int>(devices.size())) {
      throw RenderContextError("EGL: no EGL device " + std::to_string(choice.device_index) + " (found " +
                               std::to_string(devices.size()) + " device(s)" +
                               (why_none.empty() ? "" : "; " + why_none) + ")" + kHint);
    }
    for (const Device& device : devices) {
      if (choice.device_index >= 0 ? device.index != choice.device_index : !device.gpu) continue;
      const EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, device.handle, nullptr);
      const std::string why = impl_->TryDisplay(display, options);
      if (why.empty()) {
        impl_->info.platform = "device";
        impl_->info.device = device.description;
        return;
      }
      failures.push_back(device.description + ": " + why);
    }
    if (failures.empty()) failures.push_back(why_none.empty() ? "no GPU EGL device found" : why_none);
    if (choice.platform == EglPlatform::kDevice) {
      std::string message = "EGL: could not create an OpenGL context on a GPU EGL device: ";
      for (std::size_t i = 0; i < failures.size(); ++i) message += (i ? "; " : "") + failures[i];
      throw RenderContextError(message + kHint);
    }
  }

  if (!HasExtension(client, "EGL_MESA_platform_surfaceless")) {
    failures.push_back("surfaceless: EGL has no EGL_MESA_platform_surfaceless (is Mesa's libegl-mesa0 installed?)");
  } else {
    const EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    const std::string why = impl_->TryDisplay(display, options);
    if (why.empty()) {
      impl_->info.platform = "surfaceless";
      return;
    }
    failures.push_back("surfaceless: " + why);
  }
  std::string message = "EGL: could not create an OpenGL context: ";
  for (std::size_t i = 0; i < failures.size(); ++i) message += (i ? "; " : "") + failures[i];
  throw RenderContextError(message + kHint);
}

EglContext::~EglContext() = default;
EglContext::EglContext(EglContext&&) noexcept = default;
EglContext& EglContext::operator=(EglContext&&) noexcept = default;

void EglContext::MakeCurrent() const {
  if (eglGetCurrentContext() == impl_->context) return;
  if (!eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context))
    throw RenderContextError(EglFailure("EGL: eglMakeCurrent failed"));
}

const EglContextInfo& EglContext::info() const { return impl_->info; }

}  // namespace confluent
