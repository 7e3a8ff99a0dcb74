// The GL side of sim/render/mip_chain.hpp, for the renderer: include after glad.
#pragma once

#include <glad/gl.h>

namespace driftlab::sim {

/// Draws the mip levels 1 .. levels - 1 of a GL_R8 texture from its level 0 (see
/// draw_mip_levels). Needs a current context; leaves the framebuffer 0, the texture's base and
/// max levels 0 and levels - 1 and the depth test off. Its GL objects live as long as the context
/// (as the renderer's own do).
class MipChain {
 public:
  MipChain();
  MipChain(const MipChain&) = delete;
  MipChain& operator=(const MipChain&) = delete;

  void build(GLuint texture, int width, int height, int levels);

 private:
  GLuint program_ = 0, fbo_ = 0, vao_ = 0;
};

}  // namespace driftlab::sim
