#include "ObjectLevel.h"

#include "BulletProxies.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace cullide::bullet {
namespace {

bool finiteBox(const btVector3& mn, const btVector3& mx) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(mn[a]) || !std::isfinite(mx[a])) return false;
    return true;
}

/// Where a proxy with a non-finite AABB waits in the tree: a point beyond every finite box Bullet makes (planes
/// reach BT_LARGE_FLOAT), so it keeps the tree's volumes finite and meets no valid object.
btVector3 parkedPoint() {
    const btScalar far = std::numeric_limits<btScalar>::max() / btScalar(4);
    return btVector3(far, far, far);
}

std::string boxText(const btVector3& mn, const btVector3& mx) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "non-finite AABB [%g %g %g] - [%g %g %g]", double(mn.x()), double(mn.y()),
                  double(mn.z()), double(mx.x()), double(mx.y()), double(mx.z()));
    return buf;
}

}  // namespace

ObjectLevel::ObjectLevel(btOverlappingPairCache* pairCache)
    : m_tree(new btDbvtBroadphase(pairCache)) {}  // btDbvtBroadphase's aligned operator new

void ObjectLevel::replace(std::unique_ptr<btBroadphaseInterface> level) {
    m_tree = std::move(level);
    m_parked.clear();
}

btBroadphaseProxy* ObjectLevel::createProxy(const btVector3& mn, const btVector3& mx, int shapeType, void* userPtr,
                                            int group, int mask, btDispatcher* dispatcher) {
    const bool finite = finiteBox(mn, mx);
    const btVector3 point = parkedPoint();
    btBroadphaseProxy* p =
        m_tree->createProxy(finite ? mn : point, finite ? mx : point, shapeType, userPtr, group, mask, dispatcher);
    ++m_proxyCount;
    if (!finite) park(p, "createProxy", boxText(mn, mx), dispatcher);
    return p;
}

void ObjectLevel::setAabb(btBroadphaseProxy* p, const btVector3& mn, const btVector3& mx, btDispatcher* dispatcher) {
    if (!finiteBox(mn, mx)) {
        park(p, "setAabb", boxText(mn, mx), dispatcher);
        return;
    }
    unpark(p);
    m_tree->setAabb(p, mn, mx, dispatcher);
}

void ObjectLevel::destroyProxy(btBroadphaseProxy* p, btDispatcher* dispatcher) {
    unpark(p);
    m_tree->destroyProxy(p, dispatcher);
    --m_proxyCount;
}

/// No pairs, a mask of 0 so that none are made, reported once per parking.
void ObjectLevel::park(btBroadphaseProxy* p, const char* where, const std::string& why, btDispatcher* dispatcher) {
    ++m_parkCalls;
    const auto [it, added] = m_parked.emplace(p, p->m_collisionFilterMask);
    const btVector3 point = parkedPoint();
    m_tree->setAabb(p, point, point, dispatcher);
    if (!added) return;
    p->m_collisionFilterMask = 0;
    cache()->removeOverlappingPairsContainingProxy(p, dispatcher);
    std::fprintf(stderr,
                 "cullide::CullideBroadphase: %s: collision object %p (proxy %d) rejected: %s. It gets no pairs "
                 "until its AABB is finite again; every other object is unaffected. (Reported each time it is "
                 "parked; getRejectedCount() counts every call.)\n",
                 where, static_cast<const void*>(objectOf(p)), p->m_uniqueId, why.c_str());
}

void ObjectLevel::unpark(btBroadphaseProxy* p) {
    if (m_parked.empty()) return;  // the common case: no hash lookup per setAabb
    const auto it = m_parked.find(p);
    if (it == m_parked.end()) return;
    p->m_collisionFilterMask = it->second;
    m_parked.erase(it);
}

}  // namespace cullide::bullet
