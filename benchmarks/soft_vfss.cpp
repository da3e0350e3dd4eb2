// cullide-bench-softbody: would restricting Bullet's soft-soft face collisions (VF_SS) to CULLIDE's surviving faces
// pay? (issue #3: "where soft bodies collide through faces, the culler's surviving faces restrict the candidates if
// that pays (measure it)").
//
// Two soft tori fall on each other under Bullet's default pipeline (cullide::demo::SoftToriScene, shared with
// tests/bullet/softbody_test.cpp, at several resolutions). At first touch (step 20) and once settled (step 150) it
// times, per step:
//   - Bullet's whole VF_SS stage for the pair: btSoftBody::defaultCollisionHandler(other) (node tree of each body
//     against the face tree of the other, contact generation);
//   - what a restriction would have to pay before saving anything: the soft bodies' faces handed to the culler as
//     two triangle meshes (nodes copied, culling distance = both margins + 2 * the largest node displacement this
//     step, VF_SS's own per-node allowance), one culler run.
// If the culler run alone costs more than the whole VF_SS stage, no restriction of that stage can pay.
//
//   cullide-bench-softbody [--repeats N]
#include "cullide/Culler.h"
#include "cullide/Timer.h"
#include "cullide/demo/SoftToriScene.h"

#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

using cullide::TriangleMesh;
using cullide::Vec3;

struct Measurement {
    int steps = 0;
    int nodes = 0;
    int faces = 0;
    double vfssMs = 0.0;
    std::size_t contacts = 0;
    double cullMs = 0.0;
    double cullDistance = 0.0;
    std::size_t survivingFaces = 0;
};

/// The faces of a soft body as a triangle mesh over its current node positions.
TriangleMesh facesOf(const btSoftBody& sb) {
    TriangleMesh mesh;
    mesh.vertices.reserve(static_cast<std::size_t>(sb.m_nodes.size()));
    for (int i = 0; i < sb.m_nodes.size(); ++i) {
        const btVector3& x = sb.m_nodes[i].m_x;
        mesh.vertices.emplace_back(double(x.x()), double(x.y()), double(x.z()));
    }
    mesh.triangles.reserve(static_cast<std::size_t>(sb.m_faces.size()));
    const btSoftBody::Node* first = &sb.m_nodes[0];
    for (int i = 0; i < sb.m_faces.size(); ++i) {
        const btSoftBody::Face& f = sb.m_faces[i];
        mesh.triangles.push_back({static_cast<std::uint32_t>(f.m_n[0] - first),
                                  static_cast<std::uint32_t>(f.m_n[1] - first),
                                  static_cast<std::uint32_t>(f.m_n[2] - first)});
    }
    return mesh;
}

Measurement measure(int segments, int sides, int steps, int repeats) {
    btSoftBodyRigidBodyCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    cullide::demo::prepareSoftWorld(world);

    const cullide::demo::SoftToriScene scene(world, segments, sides);
    for (int s = 0; s < steps; ++s) world.stepSimulation(btScalar(1.0 / 60.0), 1, btScalar(1.0 / 60.0));

    btSoftBody& a = scene.torus(0);
    btSoftBody& b = scene.torus(1);
    Measurement m;
    m.steps = steps;
    m.nodes = a.m_nodes.size();
    m.faces = a.m_faces.size();

    // Bullet's VF_SS stage for the pair, as btSoftSoftCollisionAlgorithm runs it once per step.
    a.defaultCollisionHandler(&b);  // warm-up
    double vfss = 0.0;
    for (int r = 0; r < repeats; ++r) {
        a.m_scontacts.resize(0);
        b.m_scontacts.resize(0);
        cullide::Timer t;
        a.defaultCollisionHandler(&b);
        vfss += t.ms();
        m.contacts = static_cast<std::size_t>(a.m_scontacts.size() + b.m_scontacts.size());
    }
    m.vfssMs = vfss / repeats;

    // VF_SS's per-node allowance: margins plus twice the node's displacement this step.
    double displacement = 0.0;
    for (const btSoftBody* sb : {&a, &b})
        for (int i = 0; i < sb->m_nodes.size(); ++i)
            displacement = std::max(displacement, double((sb->m_nodes[i].m_x - sb->m_nodes[i].m_q).length()));
    cullide::Settings settings;
    settings.margin = double(a.getCollisionShape()->getMargin() + b.getCollisionShape()->getMargin()) +
                      2.0 * displacement;
    settings.exactTriangles = false;
    m.cullDistance = settings.margin;
    std::unique_ptr<cullide::Culler> culler = cullide::createGpuCuller(settings);
    cullide::Result result;
    double cull = 0.0;
    for (int r = 0; r <= repeats; ++r) {
        cullide::Timer t;
        const TriangleMesh meshA = facesOf(a);
        const TriangleMesh meshB = facesOf(b);
        std::vector<cullide::Object> objects(2);
        objects[0].mesh = &meshA;
        objects[1].mesh = &meshB;
        culler->run(objects, result);
        if (r > 0) cull += t.ms();  // run 0 warms up
    }
    m.cullMs = cull / repeats;
    for (const auto& list : result.pcsTriangles) m.survivingFaces += list.size();

    return m;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 20;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--repeats") == 0 && i + 1 < argc) {
            repeats = std::max(1, std::atoi(argv[++i]));
        } else {
            std::fprintf(stderr, "usage: %s [--repeats N]\n", argv[0]);
            return 2;
        }
    }
    try {
        std::printf("| nodes per torus | faces per torus | state | Bullet VF_SS ms (pair, whole stage) | VF_SS contacts | "
                    "culling distance | CULLIDE run on the faces ms | surviving faces (both tori) |\n");
        std::printf("|---|---|---|---|---|---|---|---|\n");
        const int resolutions[][2] = {{24, 10}, {48, 20}, {96, 40}};
        for (const auto& r : resolutions) {
            for (const int steps : {20, 150}) {  // first touch, settled
                const Measurement m = measure(r[0], r[1], steps, repeats);
                std::printf("| %d | %d | step %d | %.3f | %zu | %.3f | %.3f | %zu of %d |\n", m.nodes, m.faces,
                            m.steps, m.vfssMs, m.contacts, m.cullDistance, m.cullMs, m.survivingFaces, 2 * m.faces);
                std::fflush(stdout);
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide-bench-softbody: %s\n", e.what());
        return 1;
    }
    return 0;
}
