// An off-screen OpenGL 4.5 core context, with the gl* functions loaded by glad through the
// backend's own GetProcAddress (immune to link order: with -lGL before -lOSMesa, plain gl*
// calls resolve to glvnd and glGetString returns NULL). Backends: OSMesa (Mesa llvmpipe on any
// CPU, the default) and EGL (surfaceless or pbuffer: Mesa on a CPU, the vendor driver on a GPU).
#pragma once

#include <memory>
#include <string>

#include "sim/render/render_options.hpp"

namespace driftlab::sim {

class GlContext {
 public:
  virtual ~GlContext() = default;
  /// Makes this context current on the calling thread.
  virtual void make_current() = 0;
  /// "OpenGL 4.5 (Core Profile) Mesa 22.3.6 / llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string description() const { return description_; }

 protected:
  std::string description_;
};

/// Creates a context of `backend` and loads the GL functions. Throws UserError
/// naming the backend and what failed (no EGL display, no 4.5 core profile, ...).
std::unique_ptr<GlContext> create_gl_context(RenderBackend backend);

}  // namespace driftlab::sim
