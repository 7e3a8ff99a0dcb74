#include "sim/render/mip_chain.hpp"

#include "sim/render/mip_chain_gl.hpp"

#include <algorithm>
#include <cstddef>

#include "sim/render/gl_context.hpp"
#include "sim/render/gl_program.hpp"
#include "sim/render/shaders.hpp"

namespace driftlab::sim {

int mip_level_count(int width, int height) {
  int levels = 1;
  for (int m = std::max(width, height); m > 1; m /= 2) ++levels;
  return levels;
}

MipChain::MipChain() {
  program_ = link_program(shaders::kMipVs, shaders::kMipFs, "mip level");
  glGenFramebuffers(1, &fbo_);
  glGenVertexArrays(1, &vao_);
}

void MipChain::build(GLuint texture, int width, int height, int levels) {
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "u_src"), 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, texture);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glBindVertexArray(vao_);
  int w = width, h = height;
  for (int level = 1; level < levels; ++level) {
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
    // Sampling only the level above while drawing this one: no feedback loop.
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, level - 1);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, level - 1);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, level);
    glViewport(0, 0, w, h);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, levels - 1);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, 0, 0);
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

std::vector<GrayImage> draw_mip_levels(const GrayImage& base, RenderBackend backend) {
  const auto context = create_gl_context(backend);
  const int levels = mip_level_count(base.width, base.height);
  GLuint texture = 0;
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexStorage2D(GL_TEXTURE_2D, levels, GL_R8, base.width, base.height);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, base.width, base.height, GL_RED, GL_UNSIGNED_BYTE,
                  base.pixels.data());
  MipChain().build(texture, base.width, base.height, levels);
  std::vector<GrayImage> out;
  glBindTexture(GL_TEXTURE_2D, texture);
  int w = base.width, h = base.height;
  for (int level = 1; level < levels; ++level) {
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
    GrayImage img;
    img.width = w;
    img.height = h;
    img.pixels.resize(static_cast<std::size_t>(w) * h);
    glGetTexImage(GL_TEXTURE_2D, level, GL_RED, GL_UNSIGNED_BYTE, img.pixels.data());
    out.push_back(std::move(img));
  }
  glDeleteTextures(1, &texture);
  return out;
}

}  // namespace driftlab::sim
