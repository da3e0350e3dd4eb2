#include "gl/GlBuffers.h"

#include <algorithm>

namespace cullide::gl {

void reserveBuffer(GLuint buffer, std::size_t& capacity, std::size_t bytes) {
    if (bytes > capacity || capacity == 0) {
        capacity = std::max<std::size_t>({bytes, capacity + capacity / 2, 256});
        glNamedBufferData(buffer, static_cast<GLsizeiptr>(capacity), nullptr, GL_DYNAMIC_DRAW);
    }
}

void growKeeping(GLuint& buffer, std::size_t& capacity, std::size_t used, std::size_t bytes) {
    if (bytes <= capacity && capacity != 0) return;
    const std::size_t grown = std::max<std::size_t>({bytes, 2 * capacity, 256});
    GLuint bigger = 0;
    glCreateBuffers(1, &bigger);
    glNamedBufferData(bigger, static_cast<GLsizeiptr>(grown), nullptr, GL_DYNAMIC_DRAW);
    if (used > 0) glCopyNamedBufferSubData(buffer, bigger, 0, 0, static_cast<GLsizeiptr>(std::min(used, capacity)));
    glDeleteBuffers(1, &buffer);
    buffer = bigger;
    capacity = grown;
}

void uploadBuffer(GLuint buffer, std::size_t& capacity, const void* data, std::size_t bytes) {
    reserveBuffer(buffer, capacity, bytes);
    if (bytes > 0) glNamedBufferSubData(buffer, 0, static_cast<GLsizeiptr>(bytes), data);
}

std::size_t uploadAfterPrefix(GLuint buffer, std::size_t& capacity, std::size_t& valid, const void* data,
                              std::size_t bytes, std::size_t keepBytes) {
    if (bytes > capacity || capacity == 0) {
        reserveBuffer(buffer, capacity, bytes);
        keepBytes = 0;
    }
    keepBytes = std::min({keepBytes, valid, bytes});
    if (bytes > keepBytes)
        glNamedBufferSubData(buffer, static_cast<GLintptr>(keepBytes), static_cast<GLsizeiptr>(bytes - keepBytes),
                             static_cast<const unsigned char*>(data) + keepBytes);
    valid = bytes;
    return bytes - keepBytes;
}

}  // namespace cullide::gl
