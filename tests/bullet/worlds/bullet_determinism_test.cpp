// Issue #6: the same input gives the same Bullet contacts, run after run and whatever the culler's thread count.
#include "SceneSupport.h"
#include "TorusScene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

namespace cullide::test {
namespace {

/// Every contact point of every manifold after each step, in a canonical order, bit for bit.
std::vector<std::array<double, 10>> contactsOf(TestWorld& w) {
    std::vector<std::array<double, 10>> out;
    btCollisionDispatcher& d = w.dispatcher();
    for (int i = 0; i < d.getNumManifolds(); ++i) {
        const btPersistentManifold* m = d.getManifoldByIndexInternal(i);
        const double a = double(static_cast<const btCollisionObject*>(m->getBody0())->getUserIndex());
        const double b = double(static_cast<const btCollisionObject*>(m->getBody1())->getUserIndex());
        for (int c = 0; c < m->getNumContacts(); ++c) {
            const btManifoldPoint& p = m->getContactPoint(c);
            out.push_back({a, b, double(p.getPositionWorldOnA().x()), double(p.getPositionWorldOnA().y()),
                           double(p.getPositionWorldOnA().z()), double(p.m_normalWorldOnB.x()),
                           double(p.m_normalWorldOnB.y()), double(p.m_normalWorldOnB.z()), double(p.getDistance()),
                           double(p.getAppliedImpulse())});
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST(BulletDeterminism, SameContactsAcrossRunsAndThreadCounts) {
    // Issue #6: the same input gives the same Bullet contacts, run after run and whatever the culler's thread
    // count (the candidate search runs on a worker pool; its output order must not depend on scheduling).
    CULLIDE_BULLET_REQUIRE_GL();
    TorusScene scene;
    std::vector<std::vector<std::array<double, 10>>> runs[3];
    const unsigned threads[3] = {1, 2, 1};
    for (int r = 0; r < 3; ++r) {
        Settings settings;
        settings.threads = threads[r];
        TestWorld w(PipelineKind::Cullide, {}, settings);
        w.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
        scene.populate(w);
        for (int step = 0; step < 150; ++step) {
            w.step();
            runs[r].push_back(contactsOf(w));
        }
    }
    std::size_t contacts = 0;
    for (const auto& s : runs[0]) contacts += s.size();
    EXPECT_GT(contacts, 1000u) << "the scene must be in contact for most of the run";
    for (int r = 1; r < 3; ++r)
        for (std::size_t step = 0; step < runs[0].size(); ++step)
            ASSERT_EQ(runs[0][step], runs[r][step]) << "run " << r << " (threads " << threads[r] << ") step " << step;
}

}  // namespace
}  // namespace cullide::test
