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
    for (const std::vector<StaticEntry*>* entries : {&lookup.entry, &lookup.moving})
        for (StaticEntry* e : *entries)
            if (e != nullptr) e->checked = true;
    return lookup;
}

}  // namespace cullide::test
