// The broadphase's object level: Bullet's own btDbvtBroadphase (incremental trees, fattened leaves, lazy pair
// removal, filters, the overlap filter callback, ray and box queries), so that its pair cache holds exactly the pairs
// Bullet's default pipeline would — or the application's own Bullet broadphase (replace), e.g. a btAxisSweep3 — plus
// a guard for non-finite AABBs: such a proxy would poison the tree's volumes for every object, so it is parked far
// away, at a point of its own, and its pairs removed until its box is finite (with a replaced object level, also a
// filter mask of 0 meanwhile).
#pragma once

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>

#include <cstddef>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace cullide::bullet {

class ObjectLevel {
public:
    explicit ObjectLevel(btOverlappingPairCache* pairCache);

    btBroadphaseProxy* createProxy(const btVector3& mn, const btVector3& mx, int shapeType, void* userPtr, int group,
                                   int mask, btDispatcher* dispatcher);
    void setAabb(btBroadphaseProxy* p, const btVector3& mn, const btVector3& mx, btDispatcher* dispatcher);
    void destroyProxy(btBroadphaseProxy* p, btDispatcher* dispatcher);

    /// Replaces the object level by `level` (not null; only while there are no proxies).
    void replace(std::unique_ptr<btBroadphaseInterface> level);

    /// The Bullet broadphase itself, for what it answers as Bullet's (pairs, getAabb, rayTest, aabbTest, resetPool).
    btBroadphaseInterface& tree() { return *m_tree; }
    const btBroadphaseInterface& tree() const { return *m_tree; }
    btOverlappingPairCache* cache() const { return m_tree->getOverlappingPairCache(); }

    bool isParked(const btBroadphaseProxy* p) const { return m_parked.count(p) != 0; }
    std::size_t parkedCount() const { return m_parked.size(); }
    std::size_t proxyCount() const { return m_proxyCount; }
    /// Every park() call so far (a proxy parked again by each setAabb with a non-finite box counts each time).
    std::size_t parkCalls() const { return m_parkCalls; }

private:
    /// Parks `p` at a slot of its own (takeSlot), unless it is parked already.
    void park(btBroadphaseProxy* p, const char* where, const std::string& why, btDispatcher* dispatcher);
    void unpark(btBroadphaseProxy* p);
    /// The slot the next parked proxy takes (a freed one first), and taking it.
    std::size_t nextSlot() const;
    std::size_t takeSlot();

    struct Parked {
        std::size_t slot;  ///< its far point (parkedPoint)
        int mask;          ///< its filter mask when parked: restored with a replaced object level
    };
    std::unique_ptr<btBroadphaseInterface> m_tree;
    bool m_ownTree = true;  ///< Bullet's btDbvtBroadphase made here, not a replacement
    std::size_t m_proxyCount = 0;
    std::size_t m_parkCalls = 0;
    /// Proxies with a non-finite AABB, until the AABB is finite again.
    std::unordered_map<const btBroadphaseProxy*, Parked> m_parked;
    std::vector<std::size_t> m_freeSlots;  ///< slots below m_slotCount no proxy holds
    std::size_t m_slotCount = 0;
};

}  // namespace cullide::bullet
