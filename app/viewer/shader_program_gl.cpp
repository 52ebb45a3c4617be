// GLSL compile and link with the info log turned into a flashgs::Error.
#include "shader_program_gl.h"

#include <vector>

#include "flashgs/error.h"

namespace flashgs::viewer {
namespace {

GLuint compile(const char* name, GLenum type, const char* source) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(static_cast<std::size_t>(length) + 1, '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error(std::string("shader ") + name + (type == GL_VERTEX_SHADER ? " (vertex)" : " (fragment)") +
                " does not compile: " + log.data());
  }
  return shader;
}

}  // namespace

ShaderProgram::~ShaderProgram() {
  if (m_program) glDeleteProgram(m_program);
}

void ShaderProgram::build(const char* name, const char* vertex_source, const char* fragment_source) {
  const GLuint vs = compile(name, GL_VERTEX_SHADER, vertex_source);
  GLuint fs = 0;
  try {
    fs = compile(name, GL_FRAGMENT_SHADER, fragment_source);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(static_cast<std::size_t>(length) + 1, '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error(std::string("shader ") + name + " does not link: " + log.data());
  }
  if (m_program) glDeleteProgram(m_program);
  m_program = program;
}

}  // namespace flashgs::viewer
