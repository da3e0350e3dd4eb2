// Objects given as a mesh in its own frame plus a transform (Object::transform): their conservative world boxes for
// the box pre-pass, and their world-space triangles, built only for the objects that the pre-pass keeps.
#pragma once

#include "cullide/TaskPool.h"
#include "cullide/Object.h"

#include <cstdint>
#include <vector>

namespace cullide {

/// The smallest box that holds transformPoint(t, p) for every p in `local`, rounding included: the box of the eight
/// transformed corners (transformPoint is monotone in each coordinate). Not finite when the map overflows (or `t` is
/// not finite). An empty `local` gives an empty box.
Aabb transformedBounds(const Transform& t, const Aabb& local);

/// True when every coefficient of `t` is finite.
bool isFinite(const Transform& t);

/// The frame's objects with world-space meshes: each object with a transform whose `needed` flag is set gets a
/// world-space copy of its mesh (vertices mapped by transformPoint, triangles as they are); every other object is
/// passed through as it is (a transformed object that is not needed keeps its local mesh, which nothing reads for
/// geometry). The returned objects and their meshes live until the next call.
class WorldMeshes {
public:
    const std::vector<Object>& resolve(const std::vector<Object>& objects, const std::vector<std::uint8_t>& needed,
                                       TaskPool* pool);
    /// Bytes held by the world-space copies of the last frame (capacity).
    std::size_t bytes() const;

private:
    std::vector<Object> m_objects;
    std::vector<TriangleMesh> m_meshes;  ///< one slot per object (empty unless materialised)
};

}  // namespace cullide
