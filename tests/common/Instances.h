// Scenes of shared meshes placed by transforms (Object::transform), with their world-space twins.
#pragma once

#include "cullide/Object.h"

#include <cstdint>
#include <vector>

namespace cullide::test {

/// `count` instances of a few random soups, each placed by a random rotation (some with scale and shear when
/// `affine`) and a translation that keeps them near each other in the unit cube, `farEvery`-th ones 1e6 away.
struct InstanceScene {
    std::vector<TriangleMesh> meshes;        ///< local-space meshes, shared by the instances
    std::vector<Transform> transforms;       ///< one per instance
    std::vector<std::uint32_t> meshOf;       ///< one per instance
    std::vector<TriangleMesh> worldMeshes;   ///< one per instance: transformPoint applied to its mesh

    std::vector<Object> instances() const;   ///< mesh + transform (pointers into this scene)
    std::vector<Object> worldObjects() const;  ///< the world-space twins
    void refreshWorldMeshes();                 ///< the twins after the transforms changed
};
InstanceScene randomInstances(std::uint64_t seed, int count, bool affine, int farEvery = 0);

}  // namespace cullide::test
