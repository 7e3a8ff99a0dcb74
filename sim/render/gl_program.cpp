#include "sim/render/gl_program.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

// Throws with the object's info log unless its `status` (compile or link) is set.
void check(GLuint object, GLenum status, decltype(glGetShaderiv) get_iv,
           decltype(glGetShaderInfoLog) get_log, const std::string& what) {
  GLint ok = 0;
  get_iv(object, status, &ok);
  if (ok) return;
  char log[4096];
  get_log(object, sizeof log, nullptr, log);
  throw InternalError(fmt::format("renderer: {} failed: {}", what, log));
}

GLuint compile(GLenum type, const char* source, const char* what) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  check(s, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog,
        fmt::format("{} shader compilation", what));
  return s;
}

}  // namespace

GLuint link_program(const char* vs, const char* fs, const char* what, const std::string& defines) {
  const GLuint p = glCreateProgram();
  const std::string head = "#version 450 core\n" + defines;
  const GLuint v = compile(GL_VERTEX_SHADER, (head + vs).c_str(), what);
  const GLuint f = compile(GL_FRAGMENT_SHADER, (head + fs).c_str(), what);
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  check(p, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog,
        fmt::format("{} program linking", what));
  return p;
}

}  // namespace driftlab::sim
