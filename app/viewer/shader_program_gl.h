// ShaderProgram: compiles and links a GLSL vertex + fragment pair, reporting the driver's log on failure.
#pragma once

#include <string>

#include "gl_headers_gl.h"

namespace flashgs::viewer {

class ShaderProgram {
 public:
  ShaderProgram() = default;
  ~ShaderProgram();
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  // Throws flashgs::Error with the compiler or linker log (naming the shader).
  void build(const char* name, const char* vertex_source, const char* fragment_source);
  GLuint id() const { return m_program; }
  GLint uniform(const char* name) const { return glGetUniformLocation(m_program, name); }

 private:
  GLuint m_program = 0;
};

}  // namespace flashgs::viewer
