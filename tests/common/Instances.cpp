#include "Instances.h"

#include "Compare.h"

#include <Eigen/Geometry>

#include <random>

namespace cullide::test {

std::vector<Object> InstanceScene::instances() const {
    std::vector<Object> out(transforms.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i].mesh = &meshes[meshOf[i]];
        out[i].transform = &transforms[i];
    }
    return out;
}

std::vector<Object> InstanceScene::worldObjects() const { return asObjects(worldMeshes); }

InstanceScene randomInstances(std::uint64_t seed, int count, bool affine, int farEvery) {
    InstanceScene scene;
    // Three local meshes centred near the origin (random soups live in the unit cube: shift them).
    scene.meshes = randomSoups(seed, 3, 120, 0.2);
    for (TriangleMesh& m : scene.meshes)
        for (Vec3& p : m.vertices) p -= Vec3(0.5, 0.5, 0.5);
    std::mt19937_64 rng(seed * 7919 + 1);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int i = 0; i < count; ++i) {
        Transform t;
        const Eigen::Quaterniond q(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized());
        t.linear = q.toRotationMatrix();
        if (affine && i % 2 == 1) {
            Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
            shear(0, 1) = 0.3 * unit(rng);
            t.linear = t.linear * Eigen::Vector3d(1.5 + unit(rng), 0.7, 1.2 + 0.5 * unit(rng)).asDiagonal() * shear;
        }
        t.translation = Vec3(0.5 + 0.2 * unit(rng), 0.5 + 0.2 * unit(rng), 0.5 + 0.2 * unit(rng));
        if (farEvery > 0 && i % farEvery == farEvery - 1) t.translation += Vec3(1e6, -1e6, 3e6);
        const auto mesh = static_cast<std::uint32_t>(i % static_cast<int>(scene.meshes.size()));
        scene.transforms.push_back(t);
        scene.meshOf.push_back(mesh);
    }
    scene.refreshWorldMeshes();
    return scene;
}

void InstanceScene::refreshWorldMeshes() {
    worldMeshes.clear();
    for (std::size_t i = 0; i < transforms.size(); ++i) {
        TriangleMesh world = meshes[meshOf[i]];
        for (Vec3& p : world.vertices) p = transformPoint(transforms[i], p);
        worldMeshes.push_back(std::move(world));
    }
}

}  // namespace cullide::test
