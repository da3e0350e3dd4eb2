#include "MeshCacheSupport.h"

namespace cullide::test {

Object staticObject(const TriangleMesh& mesh, std::uint64_t key, std::uint64_t version,
                    const Transform* transform) {
    Object o;
    o.mesh = &mesh;
    o.staticKey = key;
    o.version = version;
    o.transform = transform;
    return o;
}

StaticLookup lookUpAndCheck(StaticMeshCache& cache, const std::vector<Object>& objects) {
    StaticLookup lookup;
    cache.lookUp(objects, lookup);
    for (std::size_t i = 0; i < objects.size(); ++i) {
        if (lookup.entry[i] != nullptr) lookup.entry[i]->checked = true;
        if (StaticEntry* e = lookup.moving[i]) {  // placed by this frame's transform
            e->checked = true;
            e->transform = *objects[i].transform;
        }
    }
    return lookup;
}

}  // namespace cullide::test
