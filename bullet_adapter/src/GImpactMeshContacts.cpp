#include "GImpactMeshContacts.h"

#include "cullide/TaskPool.h"

#include <algorithm>

namespace cullide {
namespace detail {

void WorldTriangles::begin(int count) {
    const std::size_t n = static_cast<std::size_t>(std::max(count, 0));
    if (++m_epoch == 0) {  // wrapped: no stamp may look current
        std::fill(m_stamp.begin(), m_stamp.end(), 0u);
        m_epoch = 1;
    }
    if (m_stamp.size() < n) {
        m_stamp.resize(n, 0u);
        m_triangles.resize(static_cast<int>(n));
    }
    m_count = n;
}

btPrimitiveTriangle* WorldTriangles::get(const btGImpactMeshShapePart& part, int prim, const btTransform& t) {
    if (prim < 0 || static_cast<std::size_t>(prim) >= m_count) return nullptr;
    btPrimitiveTriangle& tri = m_triangles[prim];
    if (m_stamp[static_cast<std::size_t>(prim)] != m_epoch) {
        part.getPrimitiveTriangle(prim, tri);
        tri.applyTransform(t);
        tri.buildTriPlane();
        m_stamp[static_cast<std::size_t>(prim)] = m_epoch;
    }
    return &tri;
}

void triangleContacts(const PartPair& parts, const std::vector<int>& interleaved, WorldTriangles& world0,
                      WorldTriangles& world1, std::vector<MeshContact>& out) {
    GIM_TRIANGLE_CONTACT contact;
    for (std::size_t k = 0; k + 1 < interleaved.size(); k += 2) {
        const int face0 = interleaved[k];
        const int face1 = interleaved[k + 1];
        btPrimitiveTriangle* tri0 = world0.get(*parts.part0, face0, *parts.trans0);
        btPrimitiveTriangle* tri1 = world1.get(*parts.part1, face1, *parts.trans1);
        if (tri0 == nullptr || tri1 == nullptr) continue;  // not a primitive of the part (a stale box set)
        if (!tri0->overlap_test_conservative(*tri1) || !tri0->find_triangle_collision_clip_method(*tri1, contact))
            continue;
        // Bullet adds a triangle pair's points last to first, each with the separating normal and -depth.
        for (int j = contact.m_point_count; j-- > 0;)
            out.push_back({contact.m_points[j], contact.m_separating_normal, -contact.m_penetration_depth,
                           parts.index0, face0, parts.index1, face1});
    }
}

namespace {

/// One part pair's search from `start`, then the triangle routine on its pairs.
void searchAndTest(const LeafPairSearch& search, const NodePair& start, const PartPair& parts,
                   MeshContactScratch& scratch, std::vector<MeshContact>& out) {
    scratch.interleaved.clear();
    search.descend(start, scratch.leaves, scratch.interleaved);
    if (scratch.interleaved.empty()) return;
    scratch.world0.begin(parts.part0->getNumChildShapes());
    scratch.world1.begin(parts.part1->getNumChildShapes());
    triangleContacts(parts, scratch.interleaved, scratch.world0, scratch.world1, out);
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
            searchAndTest(search, {0, 0, true}, parts, scratch, out);
        }
    }
    lockAll(shape1, false);
    lockAll(shape0, false);
}

void MeshContactBatch::clear() {
    m_pairCount = 0;
    m_index.clear();
    m_searches.clear();
    m_tasks.clear();
}

void MeshContactBatch::add(const btCollisionObject* object0, const btCollisionObject* object1,
                           const btGImpactMeshShape& shape0, const btGImpactMeshShape& shape1,
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
    p.contacts.clear();
    p.points = Pair::Points::Pending;
    m_index[{object0, object1}] = m_pairCount;  // a pair listed twice: the last one (the same inputs)
    ++m_pairCount;
}

void MeshContactBatch::makeTasks(std::size_t target, MeshContactScratch& scratch) {
    for (std::size_t i = 0; i < m_pairCount; ++i) {
        Pair& p = m_pairs[i];
        p.firstTask = m_tasks.size();
        for (int p0 = p.shape0->getMeshPartCount(); p0-- > 0;) {
            for (int p1 = p.shape1->getMeshPartCount(); p1-- > 0;) {
                const btGImpactBoxSet& set0 = *p.shape0->getMeshPart(p0)->getBoxSet();
                const btGImpactBoxSet& set1 = *p.shape1->getMeshPart(p1)->getBoxSet();
                m_searches.emplace_back(set0, p.trans0, set1, p.trans1);
                if (!m_searches.back().rootsOverlap()) continue;
                if (target > 1 && set0.getNodeCount() >= kSplitNodes && set1.getNodeCount() >= kSplitNodes) {
                    m_searches.back().split(target, scratch.leaves, m_split);
                } else {
                    m_split.assign(1, NodePair{0, 0, true});
                }
                for (const NodePair& start : m_split) m_tasks.push_back({i, m_searches.size() - 1, p0, p1, start});
            }
        }
        p.endTask = m_tasks.size();
    }
}

void MeshContactBatch::run(TaskPool* pool, const std::function<void()>& meanwhile) {
    m_searches.clear();
    m_tasks.clear();
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
    bool made = true;
    try {
        makeTasks(threads > 1 ? 16 * threads : 1, threadScratch());
        if (m_taskContacts.size() < m_tasks.size()) m_taskContacts.resize(m_tasks.size());
        if (m_taskStateSize < m_tasks.size()) {
            m_taskState = std::make_unique<std::atomic<int>[]>(m_tasks.size());
            m_taskStateSize = m_tasks.size();
        }
    } catch (const std::exception&) {
        made = false;  // out of memory: every pair is computed by its algorithm instead
        m_tasks.clear();
        for (std::size_t i = 0; i < m_pairCount; ++i) m_pairs[i].points = Pair::Points::Failed;
    }
    for (std::size_t t = 0; t < m_tasks.size(); ++t) m_taskState[t].store(0, std::memory_order_relaxed);
    m_nextTask.store(0, std::memory_order_relaxed);
    if (pool == nullptr || threads < 2 || !made || m_tasks.empty()) {
        meanwhile();  // the algorithms run their pairs' tasks as they ask for them
        return;
    }
    // One slot per thread; each takes tasks until none is left (the calling thread once `meanwhile` returns).
    pool->parallelFor(threads, 1, [this](std::size_t, std::size_t) { work(); }, meanwhile);
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

void MeshContactBatch::work() {
    while (runNextTask()) {
    }
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
    const Pair& p = m_pairs[t.pair];
    const PartPair parts = partPair(*p.shape0, t.part0, p.trans0, *p.shape1, t.part1, p.trans1);
    std::vector<MeshContact>& out = m_taskContacts[task];
    out.clear();
    searchAndTest(m_searches[t.search], t.start, parts, scratch, out);
}

void MeshContactBatch::lockParts(bool lock) const {
    for (std::size_t i = 0; i < m_pairCount; ++i) {
        lockAll(*m_pairs[i].shape0, lock);
        lockAll(*m_pairs[i].shape1, lock);
    }
}

const std::vector<MeshContact>* MeshContactBatch::find(const btCollisionObject* object0,
                                                       const btCollisionObject* object1,
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
            for (std::size_t t = p.firstTask; t < p.endTask; ++t)
                p.contacts.insert(p.contacts.end(), m_taskContacts[t].begin(), m_taskContacts[t].end());
    }
    return p.points == Pair::Points::Ready ? &p.contacts : nullptr;
}

}  // namespace detail
}  // namespace cullide
