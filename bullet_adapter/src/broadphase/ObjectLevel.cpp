#include "broadphase/ObjectLevel.h"

#include "broadphase/BulletProxies.h"

#include <cmath>
#include <cstdio>

namespace cullide::bullet {
namespace {

bool finiteBox(const btVector3& mn, const btVector3& mx) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(mn[a]) || !std::isfinite(mx[a])) return false;
    return true;
}

/// Where the parked proxy in slot `slot` waits in the tree: a point beyond every finite box Bullet makes (planes reach
/// BT_LARGE_FLOAT, 1e18 in float builds), 2^125 ~ 4e37 on each axis, so it keeps the tree's volumes finite and meets
/// no valid object; each slot at its own z (2^104 apart: distinct floats), so parked proxies do not meet each other
/// either, whatever their filters. Slots beyond 2^21 share points (then only the filter mask keeps them apart).
btVector3 parkedPoint(std::size_t slot) {
    const double far = std::ldexp(1.0, 125);
    const double z = far + double(slot % (std::size_t{1} << 21)) * std::ldexp(1.0, 104);
    return btVector3(btScalar(far), btScalar(far), btScalar(z));
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
    m_freeSlots.clear();
    m_slotCount = 0;
    m_ownTree = false;
}

btBroadphaseProxy* ObjectLevel::createProxy(const btVector3& mn, const btVector3& mx, int shapeType, void* userPtr,
                                            int group, int mask, btDispatcher* dispatcher) {
    const bool finite = finiteBox(mn, mx);
    const btVector3 point = parkedPoint(nextSlot());  // where park() puts it: created there, not moved
    btBroadphaseProxy* p =
        m_tree->createProxy(finite ? mn : point, finite ? mx : point, shapeType, userPtr, group, mask, dispatcher);
    ++m_proxyCount;
    if (!finite) park(p, "createProxy", boxText(mn, mx), dispatcher);
    return p;
}

std::size_t ObjectLevel::nextSlot() const {
    return m_freeSlots.empty() ? m_slotCount : m_freeSlots.back();
}

std::size_t ObjectLevel::takeSlot() {
    if (m_freeSlots.empty()) return m_slotCount++;
    const std::size_t slot = m_freeSlots.back();
    m_freeSlots.pop_back();
    return slot;
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

/// No pairs: the proxy waits at its slot's far point, where it meets nothing; reported once per parking. Bullet's
/// own btDbvtBroadphase compares those points as they are, so the application's filter mask is left alone; a replaced
/// object level (a btAxisSweep3 clamps every far point onto its world box's corner) gets a mask of 0 while parked.
void ObjectLevel::park(btBroadphaseProxy* p, const char* where, const std::string& why, btDispatcher* dispatcher) {
    ++m_parkCalls;
    const auto found = m_parked.find(p);
    if (found != m_parked.end()) {  // parked already: stays where it waits
        m_tree->setAabb(p, parkedPoint(found->second.slot), parkedPoint(found->second.slot), dispatcher);
        return;
    }
    const std::size_t slot = takeSlot();
    m_parked.emplace(p, Parked{slot, p->m_collisionFilterMask});
    m_tree->setAabb(p, parkedPoint(slot), parkedPoint(slot), dispatcher);
    if (!m_ownTree) p->m_collisionFilterMask = 0;
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
    // A replaced level parked it behind a mask of 0: restored, unless the application wrote another mask meanwhile.
    if (!m_ownTree && p->m_collisionFilterMask == 0) p->m_collisionFilterMask = it->second.mask;
    m_freeSlots.push_back(it->second.slot);
    m_parked.erase(it);
}

}  // namespace cullide::bullet
