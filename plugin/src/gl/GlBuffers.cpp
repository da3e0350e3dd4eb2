#include "gl/GlBuffers.h"

#include <algorithm>
#include <cstring>

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

std::size_t uploadAfterPrefix(GLuint& buffer, std::size_t& capacity, std::size_t& valid, const void* data,
                              std::size_t bytes, std::size_t keepBytes) {
    if (bytes > capacity || capacity == 0) growKeeping(buffer, capacity, std::min(valid, keepBytes), bytes);
    keepBytes = std::min({keepBytes, valid, bytes});
    if (bytes > keepBytes)
        glNamedBufferSubData(buffer, static_cast<GLintptr>(keepBytes), static_cast<GLsizeiptr>(bytes - keepBytes),
                             static_cast<const unsigned char*>(data) + keepBytes);
    valid = bytes;
    return bytes - keepBytes;
}

std::size_t uploadChanged(GLuint& buffer, std::size_t& capacity, std::vector<unsigned char>& held, const void* data,
                          std::size_t bytes) {
    constexpr std::size_t kBlock = 64;   // compared as a whole
    constexpr std::size_t kGap = 1024;   // unchanged bytes between two runs worth a call of their own
    const auto* in = static_cast<const unsigned char*>(data);
    if (bytes > capacity || capacity == 0) growKeeping(buffer, capacity, held.size(), bytes);
    const auto changed = [&](std::size_t at) {
        const std::size_t end = std::min(at + kBlock, bytes);
        return end > held.size() || std::memcmp(in + at, held.data() + at, end - at) != 0;
    };
    std::size_t sent = 0;
    std::size_t runStart = 0, runEnd = 0;  // the run being gathered: [runStart, runEnd), empty when equal
    const auto send = [&] {
        if (runEnd == runStart) return;
        glNamedBufferSubData(buffer, static_cast<GLintptr>(runStart), static_cast<GLsizeiptr>(runEnd - runStart),
                             in + runStart);
        sent += runEnd - runStart;
    };
    for (std::size_t at = 0; at < bytes; at += kBlock) {
        if (!changed(at)) continue;
        const std::size_t end = std::min(at + kBlock, bytes);
        if (runEnd != runStart && at - runEnd < kGap) {
            runEnd = end;  // close enough: one call
            continue;
        }
        send();
        runStart = at;
        runEnd = end;
    }
    send();
    held.assign(in, in + bytes);
    return sent;
}

}  // namespace cullide::gl
