#include "sim/render/gl_context.hpp"

// glad first: it provides the GL types and refuses a system gl.h after it.
#include <glad/gl.h>
// clang-format off
#include <GL/osmesa.h>
#include <EGL/egl.h>
#include <EGL/eglext.h>
// clang-format on

#include <fmt/format.h>

#include <vector>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

std::string gl_description() {
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return fmt::format("OpenGL {} / {}", version ? version : "?", renderer ? renderer : "?");
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
    make_current();
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(OSMesaGetProcAddress)))
      throw UserError("render.backend osmesa: loading the OpenGL functions failed");
    description_ = gl_description();
  }
  ~OsmesaContext() override {
    if (ctx_) OSMesaDestroyContext(ctx_);
  }
  void make_current() override {
    // All drawing goes to framebuffer objects; the default buffer is a token 1x1.
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, 1, 1))
      throw UserError("render.backend osmesa: OSMesaMakeCurrent failed");
  }

 private:
  OSMesaContext ctx_ = nullptr;
  std::vector<unsigned char> buffer_ = std::vector<unsigned char>(16);
};

class EglContext : public GlContext {
 public:
  EglContext() {
    display_ = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    EGLint major = 0, minor = 0;
    if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, &major, &minor)) {
      // No default display (no X, no GPU device): Mesa's surfaceless platform.
      auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
          eglGetProcAddress("eglGetPlatformDisplayEXT"));
      if (get_platform_display)
        display_ =
            get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, &major, &minor))
        throw UserError(fmt::format(
            "render.backend egl: no EGL display could be initialised (EGL error 0x{:x}); use "
            "render.backend: osmesa on machines without an EGL driver",
            eglGetError()));
    }
    if (!eglBindAPI(EGL_OPENGL_API))
      throw UserError("render.backend egl: the EGL implementation has no desktop OpenGL API");
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!eglChooseConfig(display_, config_attribs, &config, 1, &n) || n < 1)
      throw UserError("render.backend egl: no EGL config with OpenGL and pbuffer support");
    const EGLint pbuffer_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    surface_ = eglCreatePbufferSurface(display_, config, pbuffer_attribs);
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
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(eglGetProcAddress)))
      throw UserError("render.backend egl: loading the OpenGL functions failed");
    description_ = gl_description();
  }
  ~EglContext() override {
    if (display_ != EGL_NO_DISPLAY) {
      eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
      if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
      eglTerminate(display_);
    }
  }
  void make_current() override {
    if (!eglMakeCurrent(display_, surface_, surface_, context_))
      throw UserError(fmt::format("render.backend egl: eglMakeCurrent failed (EGL error 0x{:x})",
                                  eglGetError()));
  }

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLSurface surface_ = EGL_NO_SURFACE;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> create_gl_context(RenderBackend backend) {
  switch (backend) {
    case RenderBackend::kOsmesa:
      return std::make_unique<OsmesaContext>();
    case RenderBackend::kEgl:
      return std::make_unique<EglContext>();
  }
  throw UserError("render.backend: unknown backend");
}

}  // namespace driftlab::sim
