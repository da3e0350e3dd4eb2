// Growing and filling GL buffers whose capacity the caller keeps (the visibility pass's storage buffers).
#pragma once

#include "gl/GlApi.h"

#include <cstddef>
#include <vector>

namespace cullide::gl {

/// Grows `buffer` to hold at least `bytes` (by half again at least; its contents are lost when it grows).
void reserveBuffer(GLuint buffer, std::size_t& capacity, std::size_t bytes);

/// Grows `buffer` to hold at least `bytes`, keeping its first `used` bytes (copied on the device into a new buffer
/// object, which replaces `buffer`).
void growKeeping(GLuint& buffer, std::size_t& capacity, std::size_t used, std::size_t bytes);

/// Grows `buffer` to at least `bytes` and uploads `data`.
void uploadBuffer(GLuint buffer, std::size_t& capacity, const void* data, std::size_t bytes);

/// Uploads `data` except its first `keepBytes`, which the buffer already holds (`valid` bytes of it are from the
/// previous upload); a buffer that has to grow keeps them (growKeeping: `buffer` may be replaced). Returns the bytes
/// sent.
std::size_t uploadAfterPrefix(GLuint& buffer, std::size_t& capacity, std::size_t& valid, const void* data,
                              std::size_t bytes, std::size_t keepBytes);

/// Uploads the parts of `data` that differ from `held` (what the buffer holds, as last sent, kept on the CPU): each
/// run of changed 64-byte blocks (runs less than 1 KiB apart sent as one); everything where nothing is held. A
/// buffer that has to grow keeps what it holds (growKeeping: `buffer` may be replaced). `held` becomes `data`.
/// Returns the bytes sent.
std::size_t uploadChanged(GLuint& buffer, std::size_t& capacity, std::vector<unsigned char>& held, const void* data,
                          std::size_t bytes);

}  // namespace cullide::gl
