// Static objects and one frame's look-up in the static mesh cache: what the mesh-cache and cluster-upload tests
// share.
#pragma once

#include "MeshCache.h"
#include "cullide/Object.h"

#include <cstdint>
#include <vector>

namespace cullide::test {

/// An object with a static key (cached between frames) at version `version`.
Object staticObject(const TriangleMesh& mesh, std::uint64_t key, std::uint64_t version = 1,
                    const Transform* transform = nullptr);

/// One frame's lookUp, with the entries marked checked (and moving ones placed) as merge() would after validation.
StaticLookup lookUpAndCheck(StaticMeshCache& cache, const std::vector<Object>& objects);

}  // namespace cullide::test
