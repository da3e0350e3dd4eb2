#include "gl/GlProgram.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace cullide::gl {
namespace {

GLenum glStage(ShaderStage stage) {
    switch (stage) {
        case ShaderStage::Compute: return GL_COMPUTE_SHADER;
        case ShaderStage::Vertex: return GL_VERTEX_SHADER;
        case ShaderStage::Fragment: return GL_FRAGMENT_SHADER;
    }
    throw std::logic_error("cullide: unknown shader stage");
}

/// Compiles one shader of `program`; throws std::runtime_error with the compiler's log.
GLuint compileShader(const ShaderProgram& program, const ShaderPieces& shader) {
    const std::string text = assembledSource(shader);
    const char* source = text.c_str();
    GLuint id = glCreateShader(glStage(shader.stage));
    glShaderSource(id, 1, &source, nullptr);
    glCompileShader(id);
    GLint ok = 0;
    glGetShaderiv(id, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetShaderInfoLog(id, sizeof log, nullptr, log);
        glDeleteShader(id);
        throw std::runtime_error(std::string("cullide: compiling ") + shader.pieces.back() + " (" + program.what +
                                 ") failed: " + log);
    }
    return id;
}

}  // namespace

GLuint linkProgram(Program which) {
    const ShaderProgram& p = shaderProgram(which);
    std::vector<GLuint> shaders;
    shaders.reserve(p.shaders.size());  // push_back cannot throw with a compiled shader in hand
    try {
        for (const ShaderPieces& shader : p.shaders) shaders.push_back(compileShader(p, shader));
    } catch (...) {
        for (GLuint shader : shaders) glDeleteShader(shader);
        throw;
    }
    GLuint program = glCreateProgram();
    for (GLuint shader : shaders) glAttachShader(program, shader);
    glLinkProgram(program);
    for (GLuint shader : shaders) glDeleteShader(shader);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetProgramInfoLog(program, sizeof log, nullptr, log);
        glDeleteProgram(program);
        throw std::runtime_error(std::string("cullide: linking ") + p.what + " failed: " + log);
    }
    return program;
}

}  // namespace cullide::gl
