#include "narrowphase/GImpactMeshContacts.h"
#include "narrowphase/GImpactConvexContacts.h"
#include "narrowphase/ApartPairs.h"

#include "cullide/TaskPool.h"

#include <BulletCollision/Gimpact/btClipPolygon.h>

#include <algorithm>
#include <new>
#include <type_traits>

namespace cullide {
namespace bullet {

namespace {
constexpr std::uint32_t kBusy = 0x80000000u;
// A slot is made anew (placement new) each time it is prepared and never destroyed.
static_assert(std::is_trivially_destructible<PreparedTriangle>::value, "a store's slots are never destroyed");
constexpr std::align_val_t kSlotAlignment{alignof(PreparedTriangle)};
}  // namespace

void TriangleStore::FreeSlots::operator()(PreparedTriangle* slots) const { ::operator delete(slots, kSlotAlignment); }

void TriangleStore::begin(const btGImpactMeshShapePart& part, const btTransform& t) {
    m_part = &part;
    // Bullet offers the part's mesh data (read here only) through a non-const accessor.
    m_mesh = const_cast<btGImpactMeshShapePart&>(part).getTrimeshPrimitiveManager();
    m_transform = t;
    m_count = 0;  // until there is room (an allocation that throws leaves an empty span)
    const std::size_t count = static_cast<std::size_t>(std::max(part.getNumChildShapes(), 0));
    if (m_capacity < count) {
        m_triangles.reset();  // no copy of the old slots: a new span prepares every triangle again
        m_stamp.reset();
        m_capacity = 0;
        m_triangles.reset(static_cast<PreparedTriangle*>(::operator new(count * sizeof(PreparedTriangle),
                                                                          kSlotAlignment)));
        m_stamp = std::make_unique<std::atomic<std::uint32_t>[]>(count);  // zero: no epoch
        m_capacity = count;
    }
    m_count = count;
    if (++m_epoch == kBusy) {  // wrapped: no stamp may look current
        for (std::size_t i = 0; i < m_capacity; ++i) m_stamp[i].store(0, std::memory_order_relaxed);
        m_epoch = 1;
    }
}

void TriangleStore::prepare(int prim, PreparedTriangle& out) const {
    m_part->getPrimitiveTriangle(prim, out.triangle);
    out.triangle.applyTransform(m_transform);
    out.triangle.buildTriPlane();
    for (int e = 0; e < 3; ++e) out.triangle.get_edge_plane(e, out.edges[e]);
}

namespace {
/// A hint that `address` will be read soon (no effect on results; never faults).
inline void prefetch(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(address);
#else
    (void)address;
#endif
}
}  // namespace

void TriangleStore::prefetchSlot(int prim) const {
    if (prim < 0 || static_cast<std::size_t>(prim) >= m_count) return;
    const std::size_t i = static_cast<std::size_t>(prim);
    prefetch(&m_stamp[i]);
    const PreparedTriangle* slot = m_triangles.get() + i;
    prefetch(slot);
    prefetch(reinterpret_cast<const char*>(slot) + 64);  // a PreparedTriangle spans two cache lines
    prefetch(m_mesh->indexbase + prim * m_mesh->indexstride);  // Bullet's own address arithmetic
}

void TriangleStore::prefetchVertices(int prim) const {
    if (prim < 0 || static_cast<std::size_t>(prim) >= m_count) return;
    const std::size_t i = static_cast<std::size_t>(prim);
    if (m_stamp[i].load(std::memory_order_relaxed) == m_epoch) return;  // prepared: its vertices are not read
    unsigned int v[3];
    m_mesh->get_indices(prim, v[0], v[1], v[2]);
    for (const unsigned int k : v) prefetch(m_mesh->vertexbase + k * m_mesh->stride);  // as Bullet's get_vertex
}

const PreparedTriangle* TriangleStore::get(int prim, PreparedTriangle& spare) {
    if (prim < 0 || static_cast<std::size_t>(prim) >= m_count) return nullptr;
    const std::size_t i = static_cast<std::size_t>(prim);
    std::atomic<std::uint32_t>& stamp = m_stamp[i];
    std::uint32_t seen = stamp.load(std::memory_order_acquire);
    PreparedTriangle* slot = m_triangles.get() + i;
    if (seen == m_epoch) return slot;
    if (seen != (m_epoch | kBusy) &&
        stamp.compare_exchange_strong(seen, m_epoch | kBusy, std::memory_order_acquire)) {
        prepare(prim, *new (slot) PreparedTriangle);
        stamp.store(m_epoch, std::memory_order_release);
        return slot;
    }
    if (seen == m_epoch) return slot;  // prepared by another thread just now
    prepare(prim, spare);  // another thread is preparing the shared copy: the same values, computed here
    return &spare;
}

namespace {

/// btPrimitiveTriangle::clip_triangle: `other` clipped by the edge planes, in Bullet's order.
int clipByEdges(const btVector4* edges, const btPrimitiveTriangle& other, btVector3* clipped) {
    btVector3 first[MAX_TRI_CLIPPING];
    int count = bt_plane_clip_triangle(edges[0], other.m_vertices[0], other.m_vertices[1], other.m_vertices[2], first);
    if (count == 0) return 0;
    btVector3 second[MAX_TRI_CLIPPING];
    count = bt_plane_clip_polygon(edges[1], first, count, second);
    if (count == 0) return 0;
    return bt_plane_clip_polygon(edges[2], second, count, clipped);
}

/// One side of the clip method: `other` clipped by `self`'s edges, the points merged against `self`'s plane.
bool clipSide(const PreparedTriangle& self, const PreparedTriangle& other, btScalar margin,
              GIM_TRIANGLE_CONTACT& side) {
    btVector3 clipped[MAX_TRI_CLIPPING];
    side.m_separating_normal = self.triangle.m_plane;
    const int count = clipByEdges(self.edges, other.triangle, clipped);
    if (count == 0) return false;
    side.merge_points(side.m_separating_normal, margin, clipped, count);
    return side.m_point_count != 0;
}

/// Whether every vertex lies beyond `plane` by more than `margin` (the distances as Bullet computes them).
bool allBeyond(const btVector4& plane, const btVector3* vertices, btScalar margin) {
    return bt_distance_point_plane(plane, vertices[0]) - margin > 0.0f &&
           bt_distance_point_plane(plane, vertices[1]) - margin > 0.0f &&
           bt_distance_point_plane(plane, vertices[2]) - margin > 0.0f;
}

/// Whether Bullet's clipping of `other` by `self`'s edge planes (clipByEdges) leaves no point at its first plane: all
/// three vertices more than SIMD_EPSILON beyond it (the distances computed as Bullet computes them). The later planes
/// clip points blended between vertices, which Bullet can extrapolate beyond the triangle (the blend aims at distance
/// 0, the classification at SIMD_EPSILON), so no such test is exact for them.
bool clippedAwayAtFirstPlane(const PreparedTriangle& self, const btPrimitiveTriangle& other) {
    return allBeyond(self.edges[0], other.m_vertices, SIMD_EPSILON);  // d - e > 0 exactly when d > e
}

}  // namespace

bool planesMayMeet(const btPrimitiveTriangle& a, const btPrimitiveTriangle& b) {
    const btScalar margin = a.m_margin + b.m_margin;
    return !allBeyond(a.m_plane, b.m_vertices, margin) && !allBeyond(b.m_plane, a.m_vertices, margin);
}

bool clipMethodContact(const PreparedTriangle& a, const PreparedTriangle& b, GIM_TRIANGLE_CONTACT& contact) {
    if (clippedAwayAtFirstPlane(b, a.triangle)) return false;  // the second side empty: the first need not be clipped
    const btScalar margin = a.triangle.m_margin + b.triangle.m_margin;
    GIM_TRIANGLE_CONTACT first;
    if (!clipSide(a, b, margin, first)) return false;
    first.m_separating_normal *= -1.f;  // pointing to `a`, as Bullet turns it
    GIM_TRIANGLE_CONTACT second;
    if (!clipSide(b, a, margin, second)) return false;
    contact.copy_from(second.m_penetration_depth < first.m_penetration_depth ? second : first);
    return true;
}

void triangleContacts(const PartPair& parts, const std::vector<int>& interleaved, TriangleStore& world0,
                      TriangleStore& world1, std::vector<MeshContact>& out) {
    GIM_TRIANGLE_CONTACT contact;
    PreparedTriangle spare0, spare1;
    // The triangles of the pairs ahead are fetched early (their store slots and indices 16 pairs ahead, the vertices
    // of those not prepared yet 8 pairs ahead): their primitives follow the box tree, scattered in the mesh's arrays,
    // and a step's data no longer sits in the caches (measured on env2 through the swap bench, two threads).
    const std::size_t n = interleaved.size();
    constexpr std::size_t kFar = 32, kNear = 16;  // in ints: two per pair
    for (std::size_t k = 0; k + 1 < n; k += 2) {
        if (k + kFar + 1 < n) {
            world0.prefetchSlot(interleaved[k + kFar]);
            world1.prefetchSlot(interleaved[k + kFar + 1]);
        }
        if (k + kNear + 1 < n) {
            world0.prefetchVertices(interleaved[k + kNear]);
            world1.prefetchVertices(interleaved[k + kNear + 1]);
        }
        const int face0 = interleaved[k];
        const int face1 = interleaved[k + 1];
        const PreparedTriangle* tri0 = world0.get(face0, spare0);
        const PreparedTriangle* tri1 = world1.get(face1, spare1);
        if (tri0 == nullptr || tri1 == nullptr) continue;  // not a primitive of the part (a stale box set)
        if (!planesMayMeet(tri0->triangle, tri1->triangle) || !clipMethodContact(*tri0, *tri1, contact))
            continue;
        // Bullet adds a triangle pair's points last to first, each with the separating normal and -depth.
        for (int j = contact.m_point_count; j-- > 0;)
            out.push_back({contact.m_points[j], contact.m_separating_normal, -contact.m_penetration_depth,
                           parts.index0, face0, parts.index1, face1});
    }
}

namespace {

/// One part pair's search from `start`, then the triangle routine on its pairs with the parts' triangles from
/// `world0` and `world1` (begun for these parts and transforms).
void searchAndTest(const LeafPairSearch& search, const NodePair& start, const PartPair& parts,
                   MeshContactScratch& scratch, TriangleStore& world0, TriangleStore& world1,
                   std::vector<MeshContact>& out) {
    scratch.interleaved.clear();
    search.descend(start, scratch.leaves, scratch.interleaved);
    if (scratch.interleaved.empty()) return;
    triangleContacts(parts, scratch.interleaved, world0, world1, out);
}

PartPair partPair(const btGImpactMeshShape& shape0, int index0, const btTransform& trans0,
                  const btGImpactMeshShape& shape1, int index1, const btTransform& trans1) {
    return {shape0.getMeshPart(index0), shape1.getMeshPart(index1), index0, index1, &trans0, &trans1};
}

void lockAll(const btGImpactMeshShape& shape, bool lock) {
    for (int p = 0; p < shape.getMeshPartCount(); ++p) {
        if (lock)
            shape.getMeshPart(p)->lockChildShapes();
        else
            shape.getMeshPart(p)->unlockChildShapes();
    }
}

const btGImpactMeshShape& meshOf(const btCollisionShape* shape) {
    return *static_cast<const btGImpactMeshShape*>(shape);
}

bool sameTransform(const btTransform& a, const btTransform& b) {
    return a.getOrigin() == b.getOrigin() && a.getBasis()[0] == b.getBasis()[0] &&
           a.getBasis()[1] == b.getBasis()[1] && a.getBasis()[2] == b.getBasis()[2];
}

/// A part pair's search is split when both box sets are at least this large (smaller ones are one task: many such
/// pairs already make enough tasks, and one small pair is not worth the threads).
constexpr int kSplitNodes = 2048;

}  // namespace

MeshContactScratch& threadScratch() {
    static thread_local MeshContactScratch scratch;
    return scratch;
}

void meshPairContacts(const btGImpactMeshShape& shape0, const btTransform& trans0, const btGImpactMeshShape& shape1,
                      const btTransform& trans1, MeshContactScratch& scratch, std::vector<MeshContact>& out) {
    lockAll(shape0, true);
    lockAll(shape1, true);
    for (int p0 = shape0.getMeshPartCount(); p0-- > 0;) {
        for (int p1 = shape1.getMeshPartCount(); p1-- > 0;) {
            const PartPair parts = partPair(shape0, p0, trans0, shape1, p1, trans1);
            const LeafPairSearch search(*parts.part0->getBoxSet(), trans0, *parts.part1->getBoxSet(), trans1);
            scratch.world0.begin(*parts.part0, trans0);
            scratch.world1.begin(*parts.part1, trans1);
            searchAndTest(search, {0, 0}, parts, scratch, scratch.world0, scratch.world1, out);
        }
    }
    lockAll(shape1, false);
    lockAll(shape0, false);
}

std::size_t ContactLists::size() const {
    std::size_t n = 0;
    for (std::size_t l = 0; l < m_count; ++l) n += m_first[l].size();
    return n;
}

void MeshContactBatch::clear() {
    m_pairCount = 0;
    m_convexCount = 0;
    m_dispatcher = nullptr;
    m_info = nullptr;
    m_index.clear();
    m_searches.clear();
    m_tasks.clear();
    m_storeCount = 0;
    m_storeIndex.clear();
}

std::size_t MeshContactBatch::storeFor(const btGImpactMeshShapePart& part, const btTransform& t) {
    const auto found = m_storeIndex.find(&part);
    if (found != m_storeIndex.end())
        for (std::size_t i : found->second)
            if (sameTransform(m_stores[i]->transform(), t)) return i;
    // A new store, within the budget on what the stores hold (their memory is kept for the next dispatches).
    const std::size_t count = static_cast<std::size_t>(std::max(part.getNumChildShapes(), 0));
    const std::size_t held = m_storeCount < m_stores.size() ? m_stores[m_storeCount]->capacity() : 0;
    const std::size_t grow = count > held ? count - held : 0;
    if ((m_storeTriangles + grow) * sizeof(PreparedTriangle) > m_storeBudget) return kNoStore;
    m_storeTriangles += grow;
    if (m_stores.size() == m_storeCount) m_stores.push_back(std::make_unique<TriangleStore>());
    m_stores[m_storeCount]->begin(part, t);
    m_storeIndex[&part].push_back(m_storeCount);
    return m_storeCount++;
}

MeshContactBatch::Pair& MeshContactBatch::addPair(const btCollisionObject* object0, const btCollisionObject* object1,
                                                  const btCollisionShape& shape0, const btCollisionShape& shape1,
                                                  const btTransform& trans0, const btTransform& trans1) {
    if (m_pairs.size() == m_pairCount) m_pairs.emplace_back();
    Pair& p = m_pairs[m_pairCount];
    p.object0 = object0;
    p.object1 = object1;
    p.shape0 = &shape0;
    p.shape1 = &shape1;
    p.trans0 = trans0;
    p.trans1 = trans1;
    p.firstTask = p.endTask = 0;
    p.convex = p.convexFirst = false;
    p.ahead = ConvexAhead();
    p.points = Pair::Points::Pending;
    m_index[{object0, object1}] = m_pairCount;  // a pair listed twice: the last one (the same inputs)
    ++m_pairCount;
    return p;
}

void MeshContactBatch::add(const btCollisionObject* object0, const btCollisionObject* object1,
                           const btGImpactMeshShape& shape0, const btGImpactMeshShape& shape1,
                           const btTransform& trans0, const btTransform& trans1) {
    addPair(object0, object1, shape0, shape1, trans0, trans1);
}

void MeshContactBatch::addConvex(const btCollisionObject* object0, const btCollisionObject* object1,
                                 const btCollisionShape& shape0, const btCollisionShape& shape1,
                                 const btTransform& trans0, const btTransform& trans1,
                                 btCollisionDispatcher& dispatcher,
                                 const btDispatcherInfo& info) {
    Pair& p = addPair(object0, object1, shape0, shape1, trans0, trans1);
    p.convex = true;
    p.convexFirst = shape0.getShapeType() != GIMPACT_SHAPE_PROXYTYPE;
    m_dispatcher = &dispatcher;
    m_info = &info;
    ++m_convexCount;
}

void MeshContactBatch::makeTasks(std::size_t target, MeshContactScratch& scratch) {
    for (std::size_t i = 0; i < m_pairCount; ++i) {
        Pair& p = m_pairs[i];
        p.firstTask = m_tasks.size();
        if (p.convex) {
            makeConvexTasks(i);
            p.endTask = m_tasks.size();
            continue;
        }
        const btGImpactMeshShape& shape0 = meshOf(p.shape0);
        const btGImpactMeshShape& shape1 = meshOf(p.shape1);
        for (int p0 = shape0.getMeshPartCount(); p0-- > 0;) {
            for (int p1 = shape1.getMeshPartCount(); p1-- > 0;) {
                const btGImpactBoxSet& set0 = *shape0.getMeshPart(p0)->getBoxSet();
                const btGImpactBoxSet& set1 = *shape1.getMeshPart(p1)->getBoxSet();
                m_searches.emplace_back(set0, p.trans0, set1, p.trans1);
                if (!m_searches.back().rootsOverlap()) continue;
                std::size_t store0 = kNoStore, store1 = kNoStore;
                if (target > 1 && set0.getNodeCount() >= kSplitNodes && set1.getNodeCount() >= kSplitNodes) {
                    m_searches.back().split(target, scratch.leaves, m_split);
                    // The parts' tasks share their triangles rather than each preparing those it meets.
                    store0 = storeFor(*shape0.getMeshPart(p0), p.trans0);
                    store1 = storeFor(*shape1.getMeshPart(p1), p.trans1);
                } else {
                    m_split.assign(1, NodePair{0, 0});
                }
                for (const NodePair& start : m_split)
                    m_tasks.push_back({i, m_searches.size() - 1, p0, p1, start, store0, store1});
            }
        }
        p.endTask = m_tasks.size();
    }
}

void MeshContactBatch::makeConvexTasks(std::size_t pair) {
    Pair& p = m_pairs[pair];
    const bool convexFirst = p.convexFirst;
    const btGImpactMeshShape& mesh = meshOf(convexFirst ? p.shape1 : p.shape0);
    const btCollisionShape& convex = convexFirst ? *p.shape0 : *p.shape1;
    const btTransform& meshTransform = convexFirst ? p.trans1 : p.trans0;
    const btTransform& convexTransform = convexFirst ? p.trans0 : p.trans1;
    p.ahead.breakingThreshold = bullet::manifoldBreakingThreshold(*m_dispatcher, *p.object0, *p.object1);
    for (int part = mesh.getMeshPartCount(); part-- > 0;) {
        if (m_candidates.size() == m_candidateCount) m_candidates.emplace_back();
        btAlignedObjectArray<int>& candidates = m_candidates[m_candidateCount];
        candidates.resize(0);
        convexCandidates(meshTransform, *mesh.getMeshPart(part), convex, convexTransform, candidates);
        if (candidates.size() == 0) continue;
        p.ahead.manifold = true;  // Bullet's loop makes the pair's manifold at its first candidate
        for (int end = candidates.size(); end > 0; end -= kConvexChunk) {
            Task t{pair, m_candidateCount, part, -1, NodePair{0, 0}, kNoStore, kNoStore};
            t.first = std::max(0, end - kConvexChunk);
            t.count = end - t.first;
            m_tasks.push_back(t);
        }
        ++m_candidateCount;
    }
}

void MeshContactBatch::prepareTasks(std::size_t target) {
    try {
        makeTasks(target, threadScratch());
        if (m_taskContacts.size() < m_tasks.size()) m_taskContacts.resize(m_tasks.size());
        if (m_taskCounts.size() < m_tasks.size()) m_taskCounts.resize(m_tasks.size());
        if (m_taskStateSize < m_tasks.size()) {
            m_taskState = std::make_unique<std::atomic<int>[]>(m_tasks.size());
            m_taskStateSize = m_tasks.size();
        }
    } catch (const std::exception&) {
        m_tasks.clear();  // out of memory: every pair is computed by its algorithm instead
        for (std::size_t i = 0; i < m_pairCount; ++i) m_pairs[i].points = Pair::Points::Failed;
    }
    for (std::size_t t = 0; t < m_tasks.size(); ++t) m_taskState[t].store(0, std::memory_order_relaxed);
    m_nextTask.store(0, std::memory_order_relaxed);
}

void MeshContactBatch::run(TaskPool* pool, const std::function<void()>& meanwhile) {
    m_searches.clear();
    m_tasks.clear();
    m_candidateCount = 0;
    if (m_pairCount == 0) {
        meanwhile();
        return;
    }
    struct Done {
        MeshContactBatch& batch;
        ~Done() {
            batch.m_running = false;
            batch.lockParts(false);
        }
    };
    lockParts(true);
    m_running = true;
    const Done done{*this};
    const std::size_t threads = pool != nullptr ? pool->size() : 1;
    if (threads < 2) {
        prepareTasks(1);
        meanwhile();  // the algorithms run their pairs' tasks as they ask for them
        return;
    }
    // The workers are woken first and wait while this thread makes the tasks (waking one takes about as long as
    // making them); then each thread takes tasks until none is left (this one once `meanwhile` returns).
    struct Publish {
        MeshContactBatch& batch;
        ~Publish() {  // also when making them throws: the workers must not wait for ever
            batch.m_tasksMade.store(true);
            batch.m_tasksReady.notify();
        }
    };
    m_tasksMade.store(false);
    const auto work = [this](std::size_t, std::size_t) {
        m_tasksReady.wait([this] { return m_tasksMade.load(); });
        while (runNextTask()) {
        }
    };
    pool->parallelFor(threads, 1, work, [&] {
        {
            const Publish publish{*this};
            prepareTasks(16 * threads);
        }
        meanwhile();
    });
}

bool MeshContactBatch::runNextTask() {
    const std::size_t t = m_nextTask.fetch_add(1, std::memory_order_relaxed);
    if (t >= m_tasks.size()) return false;
    int state = 1;
    try {
        runTask(t, threadScratch());
    } catch (const std::exception&) {
        state = 2;
    }
    m_taskState[t].store(state);
    m_taskDone.notify();
    return true;
}

bool MeshContactBatch::waitForTasks(const Pair& pair) {
    bool ok = true;
    for (std::size_t t = pair.firstTask; t < pair.endTask; ++t) {
        // Not done: run tasks nobody took yet (later pairs'); when none is left, a worker has this one: wait for it.
        while (m_taskState[t].load() == 0 && runNextTask()) {
        }
        m_taskDone.wait([&] { return m_taskState[t].load() != 0; });
        ok = ok && m_taskState[t].load() == 1;
    }
    return ok;
}

void MeshContactBatch::runTask(std::size_t task, MeshContactScratch& scratch) {
    const Task& t = m_tasks[task];
    Pair& p = m_pairs[t.pair];
    std::vector<MeshContact>& out = m_taskContacts[task];
    out.clear();
    if (p.convex) {
        const btCollisionObjectWrapper wrap0(nullptr, p.shape0, p.object0, p.trans0, -1, -1);
        const btCollisionObjectWrapper wrap1(nullptr, p.shape1, p.object1, p.trans1, -1, -1);
        const ConvexSides sides{p.convexFirst ? &wrap1 : &wrap0, p.convexFirst ? &wrap0 : &wrap1, p.convexFirst};
        m_taskCounts[task] = ConvexCounts();
        convexChunkContacts(sides, t.part0, &m_candidates[t.search][t.first], t.count, p.ahead.breakingThreshold,
                            *m_dispatcher, *m_info, out, m_taskCounts[task]);
        return;
    }
    const PartPair parts = partPair(meshOf(p.shape0), t.part0, p.trans0, meshOf(p.shape1), t.part1, p.trans1);
    // A part without a shared store (small, or beyond the budget): the task prepares its triangles in its own.
    const auto store = [&](std::size_t index, TriangleStore& own, const btGImpactMeshShapePart& part,
                           const btTransform& trans) -> TriangleStore& {
        if (index != kNoStore) return *m_stores[index];
        own.begin(part, trans);
        return own;
    };
    searchAndTest(m_searches[t.search], t.start, parts, scratch,
                  store(t.store0, scratch.world0, *parts.part0, *parts.trans0),
                  store(t.store1, scratch.world1, *parts.part1, *parts.trans1), out);
}

void MeshContactBatch::lockParts(bool lock) const {
    for (std::size_t i = 0; i < m_pairCount; ++i) {
        for (const btCollisionShape* shape : {m_pairs[i].shape0, m_pairs[i].shape1})
            if (shape->getShapeType() == GIMPACT_SHAPE_PROXYTYPE) lockAll(meshOf(shape), lock);
    }
}

MeshContactBatch::Pair* MeshContactBatch::computed(const btCollisionObject* object0, const btCollisionObject* object1,
                                                   const btCollisionShape* shape0, const btCollisionShape* shape1,
                                                   const btTransform& trans0, const btTransform& trans1) {
    if (!m_running) return nullptr;
    const auto it = m_index.find({object0, object1});
    if (it == m_index.end()) return nullptr;
    Pair& p = m_pairs[it->second];
    if (p.shape0 != shape0 || p.shape1 != shape1 || !sameTransform(p.trans0, trans0) ||
        !sameTransform(p.trans1, trans1))
        return nullptr;
    if (p.points == Pair::Points::Pending) {
        p.points = waitForTasks(p) ? Pair::Points::Ready : Pair::Points::Failed;
        if (p.points == Pair::Points::Ready)
            p.ahead.contacts = ContactLists(m_taskContacts.data() + p.firstTask, p.endTask - p.firstTask);
        if (p.points == Pair::Points::Ready && p.convex)
            for (std::size_t t = p.firstTask; t < p.endTask; ++t) {
                p.ahead.counts.candidates += m_taskCounts[t].candidates;
                p.ahead.counts.triangles += m_taskCounts[t].triangles;
                p.ahead.counts.unchecked += m_taskCounts[t].unchecked;
            }
    }
    return p.points == Pair::Points::Ready ? &p : nullptr;
}

const ContactLists* MeshContactBatch::find(const btCollisionObject* object0, const btCollisionObject* object1,
                                           const btCollisionShape* shape0, const btCollisionShape* shape1,
                                           const btTransform& trans0, const btTransform& trans1) {
    const Pair* p = computed(object0, object1, shape0, shape1, trans0, trans1);
    return p != nullptr && !p->convex ? &p->ahead.contacts : nullptr;
}

const MeshContactBatch::ConvexAhead* MeshContactBatch::findConvex(
    const btCollisionObject* object0, const btCollisionObject* object1, const btCollisionShape* shape0,
    const btCollisionShape* shape1, const btTransform& trans0, const btTransform& trans1,
    const btDispatcherInfo& info) {
    if (&info != m_info) return nullptr;  // another dispatch's settings (a nested dispatch, an own near callback)
    const Pair* p = computed(object0, object1, shape0, shape1, trans0, trans1);
    return p != nullptr && p->convex ? &p->ahead : nullptr;
}

}  // namespace bullet
}  // namespace cullide
