#include "MappedVertices.h"

#include "KeptCapacity.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace cullide {

bool MappedVertices::beginUpload(std::vector<double>& values) {
    ++m_upload;
    std::size_t live = 0;
    for (auto it = m_slots.begin(); it != m_slots.end();) {
        if (m_frame - it->second.lastFrame > kKeepFrames) {
            it = m_slots.erase(it);
        } else {
            live += it->second.count;
            ++it;
        }
    }
    if (values.size() / 3 <= 2 * live + 1024) return false;
    m_slots.clear();  // mostly dropped slots: the live ones are placed again
    values.clear();
    return true;
}

MappedVertices::Slot MappedVertices::place(const TriangleMesh& mesh, std::vector<double>& values) {
    const auto count = static_cast<std::uint32_t>(mesh.vertices.size());
    auto [it, added] = m_slots.try_emplace(&mesh);
    Entry& e = it->second;
    if (!added && e.count != count) {  // another mesh at the same address (or this one resized): a new slot
        added = true;
        e = Entry{};
    }
    if (added) {
        e.base = static_cast<std::uint32_t>(values.size() / 3);
        e.count = count;
        resizeKeeping(values, values.size() + 3 * std::size_t{count});
        // Never equal to a vertex (NaN), so write() finds it changed. (An appended slot lies past what the device
        // held at the last upload: it is sent whatever write() finds.)
        std::fill(values.end() - 3 * static_cast<std::ptrdiff_t>(count), values.end(),
                  std::numeric_limits<double>::quiet_NaN());
    }
    Slot slot;
    slot.base = e.base;
    slot.placedBefore = !added && e.lastUpload == m_upload;
    e.lastUpload = m_upload;
    e.lastFrame = m_frame;
    return slot;
}

std::size_t MappedVertices::write(const TriangleMesh& mesh, std::uint32_t base, std::vector<double>& values) {
    std::size_t first = values.size();
    std::size_t at = 3 * std::size_t{base};
    for (const Vec3& v : mesh.vertices) {
        for (int a = 0; a < 3; ++a, ++at) {
            if (first == values.size() && std::memcmp(&values[at], &v[a], sizeof(double)) != 0) first = at;
            values[at] = v[a];
        }
    }
    return first;
}

}  // namespace cullide
