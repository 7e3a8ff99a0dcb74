#include "sim/render/gl_program.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

GLuint compile(GLenum type, const char* source, const char* what) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw InternalError(fmt::format("renderer: {} shader failed to compile: {}", what, log));
  }
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
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    throw InternalError(fmt::format("renderer: {} program failed to link: {}", what, log));
  }
  return p;
}

}  // namespace driftlab::sim
