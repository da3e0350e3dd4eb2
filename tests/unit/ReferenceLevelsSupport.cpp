#include "ReferenceLevelsSupport.h"

#include "CullerBackends.h"

namespace cullide::test {

Settings referenceLevels(Pipeline pipeline, Mode mode, int resolution) {
    Settings s;
    s.pipeline = pipeline;
    s.mode = mode;
    s.resolution = resolution;
    s.gpuLevels = GpuLevels::Always;
    s.exactThreshold = 0;
    return s;
}

std::unique_ptr<Culler> referenceLevelsCuller(const Settings& s) {
    return createGpuCuller(s, createReferencePruningBackend);
}

/// Unit cubes (12 triangles each) at the given corners.
std::vector<TriangleMesh> cubesAt(const std::vector<Vec3>& corners) {
    std::vector<TriangleMesh> meshes;
    for (const Vec3& c : corners) {
        TriangleMesh m;
        for (int i = 0; i < 8; ++i) m.vertices.push_back(c + Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
        m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
        meshes.push_back(std::move(m));
    }
    return meshes;
}

}  // namespace cullide::test
