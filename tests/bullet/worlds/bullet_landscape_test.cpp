// Scene 1: primitives (boxes, spheres, capsules) and convex hulls dropped on a static btBvhTriangleMeshShape
// landscape, CULLIDE against Bullet's default pipeline.
#include "SceneSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace cullide::test {
namespace {

struct LandscapeScene {
    ShapeStore shapes;
    btCollisionShape* ground = nullptr;
    btCollisionShape* box = nullptr;
    btCollisionShape* sphere = nullptr;
    btCollisionShape* capsule = nullptr;
    btCollisionShape* hull = nullptr;
    int grid = 5;
    btScalar spacing = 7;
    bool withHulls = true;

    LandscapeScene() {
        ground = shapes.landscape(48, 1, btScalar(1.5));
        box = shapes.box(btVector3(btScalar(0.5), btScalar(0.4), btScalar(0.6)));
        sphere = shapes.sphere(btScalar(0.5));
        capsule = shapes.capsule(btScalar(0.3), btScalar(0.8));
        hull = shapes.hull(btVector3(btScalar(0.7), btScalar(0.5), btScalar(0.6)), 24, 7);
    }

    void populate(TestWorld& w) const {
        w.addBody(ground, 0, btTransform::getIdentity());
        int k = 0;
        for (int i = 0; i < grid; ++i)
            for (int j = 0; j < grid; ++j, ++k) {
                btCollisionShape* shape = k % 4 == 0   ? box
                                          : k % 4 == 1 ? sphere
                                          : k % 4 == 2 ? capsule
                                          : withHulls  ? hull
                                                       : box;
                btTransform t(btQuaternion(btVector3(btScalar(0.3), 1, btScalar(0.2)).normalized(),
                                           btScalar(0.4) * btScalar(k)),
                              btVector3(spacing * btScalar(i - grid / 2), btScalar(3 + k % 3),
                                        spacing * btScalar(j - grid / 2)));
                w.addBody(shape, 1, t);
            }
    }
};

TEST(BulletLandscape, NoContactMissingAndContactsAgree) {
    CULLIDE_BULLET_REQUIRE_GL();
    LandscapeScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the hull-mesh triangle path (off by default)
    scene.populate(reference);
    scene.populate(cullide);
    MirrorOptions options;
    // Hull-landscape pairs go through CULLIDE's triangle list in sorted triangle order, Bullet's BVH visits them in
    // tree order: the 4-point manifold reduction then keeps different points, whose depths differ by less than
    // the breaking threshold (0.02, the manifold's point-merging radius). Every other pair runs Bullet's own
    // algorithm on identical input: exact.
    options.tolerance = [](const std::pair<int, int>& pair) {
        const bool hullOnGround = pair.first == 0 && pair.second % 4 == 0;
        return hullOnGround ? double(gContactBreakingThreshold) : 1e-6;
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("landscape", run);
    expectCulledAgreement(run, 1000);  // the hull-mesh path was used
}

struct TrajectoryComparison {
    double isolatedMax = 0.0;     ///< objects never paired with another dynamic object (either pipeline)
    std::size_t isolated = 0;
    double interactingMax = 0.0;  ///< the others: solver order within a shared island differs (chaotic)
    std::size_t interacting = 0;
};

/// Marks objects that share a broadphase pair with another dynamic object (same island: solver order and sleeping
/// depend on the pair set, which legitimately differs between the pipelines).
void markInteracting(btCollisionWorld& world, std::vector<char>& interacting) {
    const btOverlappingPairCache* cache = world.getBroadphase()->getOverlappingPairCache();
    const btBroadphasePair* pairs = const_cast<btOverlappingPairCache*>(cache)->getOverlappingPairArrayPtr();
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        const auto* a = static_cast<const btCollisionObject*>(pairs[i].m_pProxy0->m_clientObject);
        const auto* b = static_cast<const btCollisionObject*>(pairs[i].m_pProxy1->m_clientObject);
        if (a->isStaticOrKinematicObject() || b->isStaticOrKinematicObject()) continue;
        interacting[std::size_t(a->getUserIndex())] = 1;
        interacting[std::size_t(b->getUserIndex())] = 1;
    }
}

TrajectoryComparison compareTrajectories(const LandscapeScene& scene, int steps) {
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(cullide);
    const std::size_t n = reference.objects().size();
    std::vector<char> interacting(n, 0);
    std::vector<double> deviation(n, 0.0);
    for (int s = 0; s < steps; ++s) {
        reference.step();
        cullide.step();
        markInteracting(reference.world(), interacting);
        markInteracting(cullide.world(), interacting);
        for (std::size_t i = 0; i < n; ++i) {
            const btVector3 d = reference.objects()[i]->getWorldTransform().getOrigin() -
                                cullide.objects()[i]->getWorldTransform().getOrigin();
            deviation[i] = std::max(deviation[i], double(d.length()));
        }
    }
    TrajectoryComparison out;
    for (std::size_t i = 1; i < n; ++i) {  // 0 is the static ground
        if (interacting[i]) {
            ++out.interacting;
            out.interactingMax = std::max(out.interactingMax, deviation[i]);
        } else {
            ++out.isolated;
            out.isolatedMax = std::max(out.isolatedMax, deviation[i]);
        }
    }
    return out;
}

TEST(BulletLandscape, TrajectoriesAgreeWhereNotChaotic) {
    CULLIDE_BULLET_REQUIRE_GL();
    LandscapeScene scene;
    scene.withHulls = false;
    const TrajectoryComparison c = compareTrajectories(scene, 240);
    std::printf("[landscape trajectories, primitives] %zu isolated objects: max deviation %.3e; %zu objects that met "
                "another: max deviation %.3e\n",
                c.isolated, c.isolatedMax, c.interacting, c.interactingMax);
    // An object alone in its island with the static ground runs Bullet's own algorithms on the same input in both
    // pipelines: identical free-running trajectories.
    EXPECT_GE(c.isolated, 15u);
    EXPECT_LT(c.isolatedMax, 1e-5);
}

TEST(BulletLandscape, HullTrajectories) {
    CULLIDE_BULLET_REQUIRE_GL();
    LandscapeScene scene;
    const TrajectoryComparison c = compareTrajectories(scene, 240);
    std::printf("[landscape trajectories, with hulls] %zu isolated objects: max deviation %.3e; %zu objects that "
                "met another: max deviation %.3e\n",
                c.isolated, c.isolatedMax, c.interacting, c.interactingMax);
    // Hull-landscape manifolds keep different (equally valid) points (sorted vs BVH triangle order), and hulls
    // rolling down hills amplify that: only the settling is checked, not the path.
    EXPECT_LT(c.isolatedMax, 3.0);
}

}  // namespace
}  // namespace cullide::test
