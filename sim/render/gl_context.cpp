#include "sim/render/gl_context.hpp"

// glad first: it provides the GL types and refuses a system gl.h after it.
#include <glad/gl.h>
// clang-format off
#include <GL/osmesa.h>
#include <EGL/egl.h>
#include <EGL/eglext.h>
// clang-format on

#include <fmt/format.h>

#include <array>
#include <atomic>
#include <mutex>
#include <vector>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

std::string gl_description() {
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return fmt::format("OpenGL {} / {}", version ? version : "?", renderer ? renderer : "?");
}

// glad keeps one set of gl* function pointers for the whole process. Contexts of one backend
// share them; a context of the other backend (OSMesa and EGL in one process, as the renderer
// tests do) reloads them when it is made current, or its calls would go to the other library.
std::atomic<GLADloadfunc> g_loaded_by{nullptr};

// Live contexts by backend, so that mixing them fails with a clear error (create_gl_context).
std::array<std::atomic<int>, 2> g_live_contexts{};

// Counts one live context of `backend` for as long as it exists.
class LiveCount {
 public:
  explicit LiveCount(RenderBackend backend) : slot_(&g_live_contexts[static_cast<int>(backend)]) {
    ++*slot_;
  }
  ~LiveCount() { --*slot_; }
  LiveCount(const LiveCount&) = delete;
  LiveCount& operator=(const LiveCount&) = delete;

 private:
  std::atomic<int>* slot_;
};

void load_gl_functions(GLADloadfunc loader, const char* backend) {
  if (g_loaded_by.load() == loader) return;
  g_loaded_by.store(nullptr);  // a load that fails half way leaves no backend's pointers
  if (!gladLoadGL(loader))
    throw UserError(fmt::format("render.backend {}: loading the OpenGL functions failed", backend));
  g_loaded_by.store(loader);
}

class OsmesaContext : public GlContext {
 public:
  OsmesaContext() {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           4,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           5,
                           0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_)
      throw UserError(
          "render.backend osmesa: OSMesaCreateContextAttribs failed to create an OpenGL 4.5 "
          "core profile context (is Mesa's libOSMesa 22 or newer installed? scripts/setup-deps "
          "installs it)");
    try {
      make_current();
    } catch (...) {
      OSMesaDestroyContext(ctx_);  // the destructor does not run for a throwing constructor
      throw;
    }
    description_ = gl_description();
  }
  ~OsmesaContext() override {
    if (ctx_) OSMesaDestroyContext(ctx_);
  }
  void make_current() override {
    // All drawing goes to framebuffer objects; the default buffer is a token 1x1.
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, 1, 1))
      throw UserError("render.backend osmesa: OSMesaMakeCurrent failed");
    load_gl_functions(reinterpret_cast<GLADloadfunc>(OSMesaGetProcAddress), "osmesa");
  }

 private:
  LiveCount live_{RenderBackend::kOsmesa};
  OSMesaContext ctx_ = nullptr;
  std::vector<unsigned char> buffer_ = std::vector<unsigned char>(16);
};

// The EGL display, tried in turn: the default one (X, Wayland, or a GPU driver that picks its
// device); the first GPU device that initialises (EGL_EXT_platform_device: NVIDIA without a
// display server); Mesa's surfaceless platform (llvmpipe on a machine without a GPU).
EGLDisplay open_display() {
  EGLint major = 0, minor = 0;
  EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor)) return d;
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (get_platform_display && query_devices) {
    std::vector<EGLDeviceEXT> devices(16);
    EGLint count = 0;
    if (query_devices(static_cast<EGLint>(devices.size()), devices.data(), &count))
      for (EGLint i = 0; i < count; ++i) {
        d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor)) return d;
      }
  }
  if (get_platform_display) {
    d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor)) return d;
  }
  throw UserError(
      fmt::format("render.backend egl: no EGL display could be initialised (EGL error 0x{:x}); use "
                  "render.backend: osmesa on machines without an EGL driver",
                  eglGetError()));
}

class EglContext : public GlContext {
 public:
  EglContext() {
    display_ = open_display();
    try {
      create_context();
    } catch (...) {
      release();  // the destructor does not run for a throwing constructor
      throw;
    }
    description_ = gl_description();
  }
  ~EglContext() override { release(); }
  void make_current() override {
    if (!eglMakeCurrent(display_, surface_, surface_, context_))
      throw UserError(fmt::format("render.backend egl: eglMakeCurrent failed (EGL error 0x{:x})",
                                  eglGetError()));
    load_gl_functions(reinterpret_cast<GLADloadfunc>(eglGetProcAddress), "egl");
  }

 private:
  // A 4.5 core context on display_, with a 1x1 pbuffer or (where there is no pbuffer config)
  // no surface, made current.
  void create_context() {
    if (!eglBindAPI(EGL_OPENGL_API))
      throw UserError("render.backend egl: the EGL implementation has no desktop OpenGL API");
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (eglChooseConfig(display_, config_attribs, &config, 1, &n) && n == 1) {
      const EGLint pbuffer_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface_ = eglCreatePbufferSurface(display_, config, pbuffer_attribs);
    } else {
      // No pbuffer configs (some GPU device displays): all drawing goes to framebuffer objects
      // anyway, so a context without any surface (EGL_KHR_surfaceless_context) will do.
      // EGL_SURFACE_TYPE defaults to EGL_WINDOW_BIT, which such displays lack as well.
      const EGLint any_attribs[] = {EGL_SURFACE_TYPE, EGL_DONT_CARE, EGL_RENDERABLE_TYPE,
                                    EGL_OPENGL_BIT, EGL_NONE};
      if (!eglChooseConfig(display_, any_attribs, &config, 1, &n) || n < 1)
        throw UserError("render.backend egl: no EGL config with desktop OpenGL support");
    }
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                      4,
                                      EGL_CONTEXT_MINOR_VERSION,
                                      5,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
    context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, context_attribs);
    if (context_ == EGL_NO_CONTEXT)
      throw UserError(fmt::format(
          "render.backend egl: creating an OpenGL 4.5 core context failed (EGL error 0x{:x})",
          eglGetError()));
    make_current();
  }
  void release() {
    if (display_ == EGL_NO_DISPLAY) return;
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
    eglTerminate(display_);
    display_ = EGL_NO_DISPLAY;
  }

  LiveCount live_{RenderBackend::kEgl};
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLSurface surface_ = EGL_NO_SURFACE;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> create_gl_context(RenderBackend backend) {
  // The check and the creation as one step, so that two threads cannot mix backends either.
  static std::mutex creating;
  const std::lock_guard<std::mutex> lock(creating);
  const RenderBackend other =
      backend == RenderBackend::kOsmesa ? RenderBackend::kEgl : RenderBackend::kOsmesa;
  if (g_live_contexts[static_cast<int>(other)].load() > 0)
    throw UserError(fmt::format(
        "render.backend {}: a renderer of backend {} is still alive in this process; OSMesa and "
        "EGL contexts share Mesa's dispatch and cannot be mixed (the first one's frames come out "
        "wrong). Destroy the other renderers first, or use one backend per process",
        yaml::enum_name(backend), yaml::enum_name(other)));
  switch (backend) {
    case RenderBackend::kOsmesa:
      return std::make_unique<OsmesaContext>();
    case RenderBackend::kEgl:
      return std::make_unique<EglContext>();
  }
  throw UserError("render.backend: unknown backend");
}

}  // namespace driftlab::sim
