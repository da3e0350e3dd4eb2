#include "SceneSupport.h"

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>

#include <cstdio>
#include <cstring>
#include <set>

namespace cullide::test {
namespace {

/// (object pair, triangle pair) keys that produced a contact point this step.
std::set<TriangleContactKey>* g_recording = nullptr;

bool recordContact(btManifoldPoint& /*cp*/, const btCollisionObjectWrapper* w0, int part0, int index0,
                   const btCollisionObjectWrapper* w1, int part1, int index1) {
    if (g_recording == nullptr) return false;
    const int a = w0->getCollisionObject()->getUserIndex();
    const int b = w1->getCollisionObject()->getUserIndex();
    if (a <= b)
        g_recording->insert(TriangleContactKey{a, part0, index0, b, part1, index1});
    else
        g_recording->insert(TriangleContactKey{b, part1, index1, a, part0, index0});
    return false;
}

void enableCallbacks(TestWorld& w) {
    for (btCollisionObject* o : w.objects())
        o->setCollisionFlags(o->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
}

}  // namespace

MirrorRun runMirrored(TestWorld& reference, TestWorld& cullide, const MirrorOptions& options) {
    MirrorRun run;
    ContactAddedCallback previous = gContactAddedCallback;
    gContactAddedCallback = recordContact;
    std::set<TriangleContactKey> defaultContacts, cullideContacts;
    for (int s = 0; s < options.steps; ++s) {
        if (options.before) options.before(s, reference, cullide);
        enableCallbacks(reference);
        enableCallbacks(cullide);
        mirrorState(reference, cullide);
        cullideContacts.clear();
        g_recording = &cullideContacts;
        cullide.detectCollisions();
        defaultContacts.clear();
        g_recording = &defaultContacts;
        reference.step();
        g_recording = nullptr;

        run.agreement.add(contactsOf(reference.world()), contactsOf(cullide.world()), options.tolerance);
        for (const TriangleContactKey& k : defaultContacts) {
            if (k[1] < 0 && k[2] < 0 && k[4] < 0 && k[5] < 0) continue;  // no triangle involved
            ++run.triangleContacts;
            if (cullideContacts.count(k) == 0) {
                ++run.triangleContactsMissing;
                if (run.firstTriangleMissing.empty()) {
                    char buf[160];
                    std::snprintf(buf, sizeof buf, "step %d: objects %d (part %d, tri %d) / %d (part %d, tri %d)", s,
                                  k[0], k[1], k[2], k[3], k[4], k[5]);
                    run.firstTriangleMissing = buf;
                }
            }
        }
        run.defaultTimes.add(reference);
        run.cullideTimes.add(cullide);
        if (const CullideCollisionDispatcher* d = cullide.cullideDispatcher()) {
            run.cullideTrianglePairs += d->getLastStepStats().trianglePairs;
            run.cullidePairsFromTriangles += d->getLastStepStats().cullidePairs;
            run.fallbackPairs += d->getLastStepStats().fallbackPairs;
            run.penetrationPairs += d->getLastStepStats().penetrationPairs;
        }
        if (const CullideBroadphase* bp = cullide.cullideBroadphase()) {
            const CullideFrameStats& f = bp->getLastFrameStats();
            run.buildMs += f.buildMs;
            run.cullMs += f.cullMs;
            run.recordMs += f.recordMs;
            run.prepassMs += f.culler.prepassMs;
            run.uploadMs += f.culler.uploadMs;
            run.gpuLevelsMs += f.culler.gpuLevelsMs;
            run.exactMs += f.culler.exactMs;
            run.cullerPairs += f.cullerPairs;
            run.cullerTriangles += f.triangles;
        }
        ++run.steps;
        if (options.each) options.each(s, reference, cullide);
    }
    gContactAddedCallback = previous;
    return run;
}

void printMirrorRun(const char* scene, const MirrorRun& run) {
    const double n = run.steps > 0 ? double(run.steps) : 1.0;
    std::printf("[%s] %zu steps\n  %s\n  %s\n", scene, run.steps, run.defaultTimes.summary("default").c_str(),
                run.cullideTimes.summary("cullide").c_str());
    std::printf("  cullide narrow phase: %.1f pairs/step fed from CULLIDE triangle lists, %.1f triangle pairs "
                "(or mesh triangles)/step, %.1f fallback pairs/step, %.2f interpenetrating GImpact pairs/step (Bullet's full "
                "algorithm)\n",
                double(run.cullidePairsFromTriangles) / n, double(run.cullideTrianglePairs) / n,
                double(run.fallbackPairs) / n, double(run.penetrationPairs) / n);
    std::printf("  cullide broadphase breakdown (ms/step): build %.3f, cull %.3f (pre-pass %.3f, upload %.3f, GPU "
                "levels %.3f, exact %.3f), records %.3f; %.0f triangles and %.1f culler pairs/step\n",
                run.buildMs / n, run.cullMs / n, run.prepassMs / n, run.uploadMs / n, run.gpuLevelsMs / n,
                run.exactMs / n, run.recordMs / n, double(run.cullerTriangles) / n, double(run.cullerPairs) / n);
    const ContactAgreement& a = run.agreement;
    std::printf("  contacts: %zu pair-steps with contacts (default), %zu missing under CULLIDE, %zu over tolerance "
                "(max |min-distance diff| %.2e), %zu pair-steps with contacts only under CULLIDE; %zu pair-steps "
                "compared point by point (position, normal, distance), %zu points without a twin\n",
                a.referencePairs, a.missingPairs, a.depthMismatches, a.maxDepthDifference, a.extraPairs,
                a.pointComparedPairs, a.pointMismatches);
    std::printf("  triangle level: %zu (pair, triangle) contact keys under default, %zu without a contact under "
                "CULLIDE\n",
                run.triangleContacts, run.triangleContactsMissing);
    std::fflush(stdout);
}

void expectCulledAgreement(const MirrorRun& run, std::size_t minimumPairSteps) {
    expectAgreement(run, minimumPairSteps);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u) << "no pair went through CULLIDE's triangle lists";
    EXPECT_EQ(run.fallbackPairs, 0u) << "pairs fell back to Bullet's full algorithm";
}

void expectAgreement(const MirrorRun& run, std::size_t minimumPairSteps) {
    EXPECT_GE(run.agreement.referencePairs, minimumPairSteps) << "too few contacts: the scene tests nothing";
    EXPECT_EQ(run.agreement.missingPairs, 0u) << run.agreement.firstMissing;
    EXPECT_EQ(run.agreement.depthMismatches, 0u) << "max diff " << run.agreement.maxDepthDifference;
    EXPECT_EQ(run.agreement.pointMismatches, 0u)
        << "contact points (position, normal, distance) of pairs that run Bullet's algorithm on identical input";
    EXPECT_EQ(run.triangleContactsMissing, 0u) << run.firstTriangleMissing;
}

std::vector<btScalar> bitState(TestWorld& w) {
    std::vector<btScalar> s;
    btCollisionDispatcher& d = w.dispatcher();
    for (int i = 0; i < d.getNumManifolds(); ++i) {
        const btPersistentManifold* m = d.getManifoldByIndexInternal(i);
        s.push_back(btScalar(static_cast<const btCollisionObject*>(m->getBody0())->getUserIndex()));
        s.push_back(btScalar(static_cast<const btCollisionObject*>(m->getBody1())->getUserIndex()));
        for (int c = 0; c < m->getNumContacts(); ++c) {
            const btManifoldPoint& p = m->getContactPoint(c);
            for (int k = 0; k < 3; ++k) s.insert(s.end(), {p.m_positionWorldOnB[k], p.m_normalWorldOnB[k]});
            s.push_back(p.m_normalWorldOnB[3]);  // kept by the manifold as the algorithm gave it
            s.insert(s.end(), {p.getDistance(), btScalar(p.getLifeTime()), p.getAppliedImpulse()});
            s.insert(s.end(), {btScalar(p.m_partId0), btScalar(p.m_index0), btScalar(p.m_partId1), btScalar(p.m_index1)});
        }
    }
    for (btCollisionObject* o : w.objects()) {
        const btRigidBody* b = btRigidBody::upcast(o);
        const btTransform& t = b->getWorldTransform();
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) s.push_back(t.getBasis()[r][c]);
        for (int c = 0; c < 3; ++c)
            s.insert(s.end(), {t.getOrigin()[c], b->getLinearVelocity()[c], b->getAngularVelocity()[c]});
    }
    return s;
}

int firstDifferingStep(TestWorld& reference, TestWorld& w, int steps, int sleepFrom) {
    int first = -1;
    for (int step = 0; step < steps; ++step) {
        if (step == sleepFrom)
            for (TestWorld* x : {&reference, &w})
                for (btCollisionObject* o : x->objects())
                    btRigidBody::upcast(o)->setSleepingThresholds(btScalar(100), btScalar(100));
        reference.step();
        w.step();
        const std::vector<btScalar> a = bitState(reference), b = bitState(w);
        if (first < 0 && (a.size() != b.size() || std::memcmp(a.data(), b.data(), a.size() * sizeof(btScalar)) != 0))
            first = step;
    }
    return first;
}

}  // namespace cullide::test
