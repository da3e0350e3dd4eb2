#include "BenchScene.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <stdexcept>

namespace cullide::bench {

namespace {

/// The rigid transform taking `from` to `to` (least squares over a spread subset of the vertices; exact for a
/// rigid motion up to rounding).
Eigen::Isometry3d recoverPose(const TriangleMesh& from, const TriangleMesh& to) {
    const std::size_t n = from.vertices.size();
    const std::size_t samples = std::min<std::size_t>(n, 256);
    Eigen::Matrix3Xd src(3, static_cast<Eigen::Index>(samples)), dst(3, static_cast<Eigen::Index>(samples));
    for (std::size_t k = 0; k < samples; ++k) {
        const std::size_t i = k * n / samples;
        src.col(static_cast<Eigen::Index>(k)) = from.vertices[i];
        dst.col(static_cast<Eigen::Index>(k)) = to.vertices[i];
    }
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.matrix() = Eigen::umeyama(src, dst, false);
    return pose;
}

}  // namespace

BenchScene::BenchScene(const SceneParams& params) : m_params(params) {
    const auto& p = params;
    if (p.name == "env1") {
        m_env = scenes::makeEnv1(p.seed, p.objects >= 0 ? p.objects : 100,
                                 p.trianglesPerObject > 0 ? p.trianglesPerObject : 200);
    } else if (p.name == "env2") {
        m_env = scenes::makeEnv2(p.seed, p.objects >= 0 ? p.objects : 6,
                                 p.trianglesPerObject > 0 ? p.trianglesPerObject : 20000);
    } else if (p.name == "env3" || p.name == "env3-deform") {
        m_env = scenes::makeEnv3(scenes::defaultDataDir(), p.name == "env3-deform", &m_standIns);
    } else {
        throw std::invalid_argument("unknown scene '" + p.name + "' (env1, env2, env3, env3-deform)");
    }
    m_local = m_env->frame(0);
    m_motion.assign(m_local.size(), Motion::Deforming);
    if (p.name == "env3") m_motion = {Motion::Rigid, Motion::Static};
    if (p.name == "env3-deform") m_motion = {Motion::Deforming, Motion::Static};
}

std::size_t BenchScene::triangleCount() const {
    std::size_t n = 0;
    for (const auto& m : m_local) n += m.triangles.size();
    return n;
}

BenchFrame BenchScene::frame(int f) {
    BenchFrame out;
    out.index = f;
    out.world = &m_env->frame(f);
    out.local = &m_local;
    out.motion = &m_motion;
    out.poses.assign(m_local.size(), Eigen::Isometry3d::Identity());
    for (std::size_t i = 0; i < m_local.size(); ++i)
        if (m_motion[i] == Motion::Rigid) out.poses[i] = recoverPose(m_local[i], (*out.world)[i]);
    return out;
}

}  // namespace cullide::bench
