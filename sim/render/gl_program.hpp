// Compiling and linking the renderer's GLSL programs: include after glad.
#pragma once

#include <glad/gl.h>

#include <string>

namespace driftlab::sim {

/// Links a program of a vertex and a fragment shader, each prefixed with "#version 450 core" and
/// `defines`. Throws InternalError with the compiler's log, naming `what`.
GLuint link_program(const char* vs, const char* fs, const char* what,
                    const std::string& defines = "");

}  // namespace driftlab::sim
