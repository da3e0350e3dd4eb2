#include "gl/GlProgram.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace cullide::gl {

GLuint compileShader(GLenum type, std::initializer_list<const char*> names) {
    std::vector<const char*> sources = {"#version 450 core\n", shaderSource("bindings.h")};
    for (const char* name : names) {
        const char* text = shaderSource(name);
        if (text == nullptr) throw std::logic_error(std::string("missing embedded shader ") + name);
        sources.push_back("\n");
        sources.push_back(text);
    }
    GLuint shader = glCreateShader(type);
    glShaderSource(shader, static_cast<GLsizei>(sources.size()), sources.data(), nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetShaderInfoLog(shader, sizeof log, nullptr, log);
        glDeleteShader(shader);
        throw std::runtime_error(std::string("cullide: compiling ") + *(names.end() - 1) + " failed: " + log);
    }
    return shader;
}

GLuint linkProgram(std::initializer_list<GLuint> shaders, const char* what) {
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
        throw std::runtime_error(std::string("cullide: linking ") + what + " failed: " + log);
    }
    return program;
}

}  // namespace cullide::gl
