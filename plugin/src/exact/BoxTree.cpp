#include "BoxTree.h"

#include "FloatRounding.h"
#include "FrameObjects.h"
#include "KeptCapacity.h"
#include "Morton.h"
#include "PoolOrHere.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#if defined(__SSE__) || defined(_M_X64)
#include <xmmintrin.h>
#define CULLIDE_BOXTREE_SSE 1
#endif
#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define CULLIDE_BOXTREE_SSE2 1
#endif

namespace cullide {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// Whether two float boxes overlap (closed intervals).
bool floatBoxesOverlap(const BoxTree::FloatBox& boxA, const BoxTree::FloatBox& boxB) {
    for (int k = 0; k < 3; ++k)
        if (boxA.lo[k] > boxB.hi[k] || boxB.lo[k] > boxA.hi[k]) return false;
    return true;
}

void clearSlot(BoxTree::Block& block, std::uint32_t slot) {
    for (int k = 0; k < 3; ++k) {
        block.lo[k][slot] = kInf;
        block.hi[k][slot] = -kInf;
    }
}

/// The float boxes of a block's leaves [0, count) (count <= kFanout) from their double boxes `leafBox`, rounded
/// outwards as floatBelow / floatAbove round (the same floats: the same IEEE operations, four lanes at a time with
/// SSE2). One conversion per coordinate of every leaf of every frame: as scalar code it was about half of a whole
/// mesh's tree build.
inline void blockFloats(const Aabb* leafBox, BoxTree::Block& block, std::size_t count) {
    std::size_t slot = 0;
#if defined(CULLIDE_BOXTREE_SSE2)
    constexpr double kMax = std::numeric_limits<float>::max();
    const __m128d low = _mm_set1_pd(-kMax), high = _mm_set1_pd(kMax);
    const __m128 absMask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
    const __m128 scale = _mm_set1_ps(0x1p-22f), tiny = _mm_set1_ps(std::numeric_limits<float>::denorm_min());
    auto toFloats = [&](double v0, double v1, double v2, double v3) {
        const __m128d a = _mm_min_pd(_mm_max_pd(_mm_set_pd(v1, v0), low), high);
        const __m128d b = _mm_min_pd(_mm_max_pd(_mm_set_pd(v3, v2), low), high);
        return _mm_movelh_ps(_mm_cvtpd_ps(a), _mm_cvtpd_ps(b));
    };
    auto slack = [&](__m128 f) { return _mm_add_ps(_mm_mul_ps(_mm_and_ps(f, absMask), scale), tiny); };
    for (; slot + 4 <= count; slot += 4) {
        const Aabb* b = leafBox + slot;
        for (int k = 0; k < 3; ++k) {
            const __m128 lo = toFloats(b[0].min[k], b[1].min[k], b[2].min[k], b[3].min[k]);
            const __m128 hi = toFloats(b[0].max[k], b[1].max[k], b[2].max[k], b[3].max[k]);
            _mm_store_ps(&block.lo[k][slot], _mm_sub_ps(lo, slack(lo)));
            _mm_store_ps(&block.hi[k][slot], _mm_add_ps(hi, slack(hi)));
        }
    }
#endif
    for (; slot < count; ++slot) {
        for (int k = 0; k < 3; ++k) {
            block.lo[k][slot] = floatBelow(leafBox[slot].min[k]);
            block.hi[k][slot] = floatAbove(leafBox[slot].max[k]);
        }
    }
}

/// The float boxes of the leaves of blocks [begin, end) of `n` leaves, from their double boxes.
inline void blocksFloats(const Aabb* leafBox, BoxTree::Block* blocks, std::size_t begin, std::size_t end,
                         std::size_t n) {
    constexpr std::size_t kFanout = BoxTree::kFanout;
    for (std::size_t b = begin; b < end; ++b)
        blockFloats(leafBox + b * kFanout, blocks[b], std::min(kFanout, n - b * kFanout));
}

std::uint32_t blocksFor(std::size_t nodes) {
    return static_cast<std::uint32_t>((nodes + BoxTree::kFanout - 1) / BoxTree::kFanout);
}

/// Leaves per chunk of the build's steps: 4096, or fewer for a pool with many workers (a tree of a few thousand
/// leaves still spreads). The tree does not depend on the chunks: bounds are unions, the sort is stable, the rest
/// writes per-index slots.
constexpr std::size_t kBuildChunk = 4096;
std::size_t buildChunk(const TaskPool* pool, std::size_t n) { return chunkFor(pool, n, 1024, kBuildChunk); }
std::size_t chunkCount(std::size_t n, std::size_t chunk) { return (n + chunk - 1) / chunk; }

}  // namespace

void BoxTree::build(const std::vector<Aabb>& boxes, const std::vector<std::uint32_t>& triangles, TaskPool* pool,
                    const std::vector<std::uint32_t>* order) {
    const std::size_t n = triangles.size();
    resizeKeeping(m_leafTriangle, n);
    m_levelCount = 0;
    m_followedOrder = false;
    if (n == 0) return;
    m_followedOrder = canFollow(triangles, order, pool) && leavesInOrder(triangles, *order, pool);
    if (!m_followedOrder) sortLeaves(boxes, triangles, pool);
    fillLeaves(boxes, pool);
    buildLevels(pool);
}

void BoxTree::buildWhole(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order, double inflate,
                         TaskPool* pool) {
    const std::size_t n = order.size();
    assignKeeping(m_leafTriangle, order.begin(), order.end());
    m_levelCount = 0;
    m_followedOrder = true;
    if (n == 0) return;
    startLeaves(n);
    const std::uint32_t* leafTriangle = m_leafTriangle.data();
    const TriangleIndices* triangles = mesh.triangles.data();
    const Vec3* vertices = mesh.vertices.data();
    Aabb* leafBox = m_leafBox.data();
    Block* blocks = m_levels[0].data();
    parallelForOrHere(pool, blocksFor(n), buildChunk(pool, n) / kFanout, [&](std::size_t begin, std::size_t end) {
        // The leaves follow a spatial order: their triangles, and those triangles' vertices, are scattered in
        // memory. Prefetch each triangle's indices 16 leaves ahead and its vertices 8 ahead.
        constexpr std::size_t kIndicesAhead = 16, kVerticesAhead = 8;
        const std::size_t last = std::min(n, end * kFanout);
        for (std::size_t i = begin * kFanout; i < last; ++i) {
            if (i + kIndicesAhead < last) __builtin_prefetch(&triangles[leafTriangle[i + kIndicesAhead]]);
            if (i + kVerticesAhead < last) {
                const TriangleIndices& ahead = triangles[leafTriangle[i + kVerticesAhead]];
                for (int k = 0; k < 3; ++k) __builtin_prefetch(&vertices[ahead[k]]);
            }
            // triangleBounds' arithmetic, written out: through its returned Aabb this loop ran 14 % slower (env3).
            const TriangleIndices& tri = triangles[leafTriangle[i]];
            const Vec3& p = vertices[tri[0]];
            const Vec3& q = vertices[tri[1]];
            const Vec3& r = vertices[tri[2]];
            Aabb& box = leafBox[i];
            for (int k = 0; k < 3; ++k) {
                box.min[k] = std::min(std::min(p[k], q[k]), r[k]) - inflate;
                box.max[k] = std::max(std::max(p[k], q[k]), r[k]) + inflate;
            }
        }
        blocksFloats(leafBox, blocks, begin, end, n);
    });
    finishLeaves(n);
    buildLevels(pool);
}

std::size_t BoxTree::buildParallelism(const TaskPool& pool, std::size_t leaves) {
    return std::min<std::size_t>(pool.size(), chunkCount(leaves, buildChunk(&pool, leaves)));
}

void BoxTree::buildMany(TaskPool& pool, std::size_t count, const std::function<std::size_t(std::size_t)>& leaves,
                        const std::function<void(std::size_t, TaskPool*)>& build) {
    std::size_t total = 0, largest = 0;
    double spreadSpan = 0.0;
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t n = leaves(i);
        total += n;
        largest = std::max(largest, n);
        spreadSpan += static_cast<double>(n) / static_cast<double>(std::max<std::size_t>(1, buildParallelism(pool, n)));
    }
    const double taskSpan = std::max(static_cast<double>(largest), static_cast<double>(total) / pool.size());
    if (count < pool.size() && spreadSpan < taskSpan) {
        for (std::size_t i = 0; i < count; ++i) build(i, &pool);
        return;
    }
    pool.parallelFor(count, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) build(i, nullptr);
    });
}

void BoxTree::sortLeaves(const std::vector<Aabb>& boxes, const std::vector<std::uint32_t>& triangles,
                         TaskPool* pool) {
    // Morton order of the box centres (10 bits per axis) over their common bounds.
    const std::size_t n = triangles.size();
    const std::size_t chunk = buildChunk(pool, n);
    const std::size_t chunks = chunkCount(n, chunk);
    assignKeeping(m_chunkBounds, chunks, Aabb{});
    const Aabb* box = boxes.data();
    const std::uint32_t* list = triangles.data();
    Aabb* chunkBounds = m_chunkBounds.data();
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t c = begin; c < end; ++c) {
            Aabb bounds;
            for (std::size_t i = c * chunk, last = std::min(n, i + chunk); i < last; ++i)
                bounds.grow(box[list[i]]);
            chunkBounds[c] = bounds;
        }
    });
    Aabb all;
    for (const Aabb& b : m_chunkBounds) all.grow(b);
    double scale[3];
    for (int k = 0; k < 3; ++k) {
        const double extent = all.max[k] - all.min[k];
        scale[k] = extent > 0.0 && std::isfinite(extent) ? 1023.0 / extent : 0.0;
    }
    resizeKeeping(m_keys, n);
    std::uint64_t* keys = m_keys.data();
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin * chunk, last = std::min(n, end * chunk); i < last; ++i) {
            const Aabb& b = box[list[i]];
            double c[3];
            for (int k = 0; k < 3; ++k)
                c[k] = (0.5 * b.min[k] + 0.5 * b.max[k] - all.min[k]) * scale[k];  // no overflow near 1e308
            keys[i] = morton::key(morton::code(c[0], c[1], c[2]), static_cast<std::uint32_t>(i));
        }
    });
    morton::sortByCode(m_keys, m_keysTmp, m_histogram, pool);
    const std::uint64_t* sorted = m_keys.data();  // the sort may have swapped the buffers
    std::uint32_t* leafTriangle = m_leafTriangle.data();
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin * chunk, last = std::min(n, end * chunk); i < last; ++i)
            leafTriangle[i] = list[static_cast<std::uint32_t>(sorted[i])];
    });
}

bool BoxTree::canFollow(const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>* order,
                        TaskPool* pool) const {
    const std::size_t n = triangles.size();
    if (order == nullptr || n * kOrderedFraction < order->size() || triangles.back() >= order->size()) return false;
    // Strictly increasing: no triangle twice, so marking them below never writes one flag from two workers.
    const std::size_t chunk = buildChunk(pool, n);
    std::vector<std::uint8_t> sorted(chunkCount(n, chunk), 1);
    parallelForOrHere(pool, sorted.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t c = begin; c < end; ++c)
            for (std::size_t i = std::max<std::size_t>(c * chunk, 1), last = std::min(n, (c + 1) * chunk); i < last;
                 ++i)
                if (triangles[i - 1] >= triangles[i]) sorted[c] = 0;
    });
    return std::all_of(sorted.begin(), sorted.end(), [](std::uint8_t s) { return s != 0; });
}

bool BoxTree::leavesInOrder(const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& order,
                            TaskPool* pool) {
    // Flag the list's triangles, then keep the flagged ones of each chunk of the order at the chunk's first leaf
    // (counted first), then clear the flags again. An order that does not hold each listed triangle once is not
    // followed.
    const std::size_t n = triangles.size();
    const std::size_t total = order.size();
    if (m_inList.size() < total) m_inList.resize(total, 0);
    std::uint8_t* inList = m_inList.data();
    const std::uint32_t* list = triangles.data();
    auto flag = [&](std::uint8_t value) {
        parallelForOrHere(pool, n, buildChunk(pool, n), [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) inList[list[i]] = value;
        });
    };
    flag(1);
    const std::size_t chunk = buildChunk(pool, total);
    const std::size_t chunks = chunkCount(total, chunk);
    m_chunkFirst.assign(chunks + 1, 0);
    const std::uint32_t* sequence = order.data();
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t c = begin; c < end; ++c) {
            std::size_t kept = 0;
            for (std::size_t i = c * chunk, last = std::min(total, i + chunk); i < last; ++i)
                kept += inList[sequence[i]];
            m_chunkFirst[c + 1] = kept;
        }
    });
    for (std::size_t c = 0; c < chunks; ++c) m_chunkFirst[c + 1] += m_chunkFirst[c];
    if (m_chunkFirst[chunks] != n) {
        flag(0);
        return false;
    }
    std::uint32_t* leafTriangle = m_leafTriangle.data();
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t c = begin; c < end; ++c) {
            std::size_t at = m_chunkFirst[c];
            for (std::size_t i = c * chunk, last = std::min(total, i + chunk); i < last; ++i)
                if (inList[sequence[i]]) leafTriangle[at++] = sequence[i];
        }
    });
    flag(0);
    return true;
}

void BoxTree::startLeaves(std::size_t n) {
    resizeKeeping(m_leafBox, n);
    if (m_levels.empty()) m_levels.emplace_back();
    resizeKeeping(m_levels[0], blocksFor(n));
}

void BoxTree::finishLeaves(std::size_t n) {
    for (auto slot = static_cast<std::uint32_t>(n % kFanout); slot != 0 && slot < kFanout; ++slot)
        clearSlot(m_levels[0].back(), slot);
    m_levelCount = 1;
    m_nodeCount.assign(1, n);
}

void BoxTree::fillLeaves(const std::vector<Aabb>& boxes, TaskPool* pool) {
    const std::size_t n = m_leafTriangle.size();
    startLeaves(n);
    const Aabb* box = boxes.data();
    const std::uint32_t* leafTriangle = m_leafTriangle.data();
    Aabb* leafBox = m_leafBox.data();
    Block* blocks = m_levels[0].data();
    parallelForOrHere(pool, blocksFor(n), buildChunk(pool, n) / kFanout, [&](std::size_t begin, std::size_t end) {
        constexpr std::size_t kAhead = 16;  // leaves follow a spatial order: their boxes are scattered in memory
        for (std::size_t i = begin * kFanout, last = std::min(n, end * kFanout); i < last; ++i) {
            if (i + kAhead < last) __builtin_prefetch(&box[leafTriangle[i + kAhead]]);
            leafBox[i] = box[leafTriangle[i]];
        }
        blocksFloats(leafBox, blocks, begin, end, n);
    });
    finishLeaves(n);
}

void BoxTree::buildLevels(TaskPool* pool) {
    // Each level the union of eight nodes below, until a single root.
    std::size_t nodes = m_nodeCount[0];
    while (nodes > 1) {
        const std::size_t parents = blocksFor(nodes);
        if (m_levels.size() == m_levelCount) m_levels.emplace_back();
        const std::vector<Block>& below = m_levels[m_levelCount - 1];
        std::vector<Block>& level = m_levels[m_levelCount];
        resizeKeeping(level, blocksFor(parents));
        // Whole blocks per task: no two tasks write one block. Levels of less than two chunks on this thread (no
        // dispatch); larger ones in chunks as the leaves' (a large tree's first level is most of this loop's work).
        const std::size_t chunk = buildChunk(pool, parents);
        TaskPool* levelPool = parents >= 2 * chunk ? pool : nullptr;
        parallelForOrHere(levelPool, level.size(), chunk / kFanout, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin * kFanout; p < std::min(parents, end * kFanout); ++p) {
                const Block& c = below[p];
                Block& block = level[p / kFanout];
                const auto slot = static_cast<std::uint32_t>(p % kFanout);
                for (int k = 0; k < 3; ++k) {
                    float lo = c.lo[k][0];
                    float hi = c.hi[k][0];
                    for (std::uint32_t i = 1; i < kFanout; ++i) {
                        lo = std::min(lo, c.lo[k][i]);
                        hi = std::max(hi, c.hi[k][i]);
                    }
                    block.lo[k][slot] = lo;
                    block.hi[k][slot] = hi;
                }
            }
        });
        for (auto slot = static_cast<std::uint32_t>(parents % kFanout); slot != 0 && slot < kFanout; ++slot)
            clearSlot(level.back(), slot);
        ++m_levelCount;
        m_nodeCount.push_back(parents);
        nodes = parents;
    }
}

inline BoxTree::FloatBox BoxTree::box(std::uint32_t level, std::uint32_t node) const {
    const Block& block = m_levels[level][node / kFanout];
    const std::uint32_t slot = node % kFanout;
    return {{block.lo[0][slot], block.lo[1][slot], block.lo[2][slot]},
            {block.hi[0][slot], block.hi[1][slot], block.hi[2][slot]}};
}

inline unsigned BoxTree::childMask(std::uint32_t level, std::uint32_t node, const FloatBox& q) const {
    const Block& c = m_levels[level - 1][node];
    unsigned mask = 0;
#ifdef CULLIDE_BOXTREE_SSE
    for (std::uint32_t h = 0; h < kFanout; h += 4) {
        __m128 ok = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(&c.lo[0][h]), _mm_set1_ps(q.hi[0])),
                               _mm_cmple_ps(_mm_set1_ps(q.lo[0]), _mm_load_ps(&c.hi[0][h])));
        for (int k = 1; k < 3; ++k)
            ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmple_ps(_mm_load_ps(&c.lo[k][h]), _mm_set1_ps(q.hi[k])),
                                           _mm_cmple_ps(_mm_set1_ps(q.lo[k]), _mm_load_ps(&c.hi[k][h]))));
        mask |= static_cast<unsigned>(_mm_movemask_ps(ok)) << h;
    }
#else
    for (std::uint32_t i = 0; i < kFanout; ++i) {
        bool ok = true;
        for (int k = 0; k < 3; ++k) ok = ok && c.lo[k][i] <= q.hi[k] && q.lo[k] <= c.hi[k][i];
        mask |= static_cast<unsigned>(ok) << i;
    }
#endif
    // Padding slots are empty boxes, but an unbounded query (coordinates beyond float range) would still meet them.
    const std::size_t children = std::min<std::size_t>(kFanout, m_nodeCount[level - 1] - std::size_t{node} * kFanout);
    return mask & ((1u << children) - 1u);
}

inline bool BoxTree::leavesOverlap(std::uint32_t leaf, const BoxTree& other, std::uint32_t otherLeaf) const {
    return m_leafBox[leaf].overlaps(other.m_leafBox[otherLeaf]);
}

inline void BoxTree::descend(const BoxTree& a, const BoxTree& b, const NodePair& p,
                             std::vector<NodePair>& pending, std::vector<TrianglePair>* out) {
    auto emit = [&](std::uint32_t levelA, std::uint32_t nodeA, std::uint32_t levelB, std::uint32_t nodeB) {
        if (levelA == 0 && levelB == 0 && out != nullptr) {
            if (a.leavesOverlap(nodeA, b, nodeB)) out->push_back({a.m_leafTriangle[nodeA], b.m_leafTriangle[nodeB]});
        } else {
            pending.push_back({levelA, nodeA, levelB, nodeB});
        }
    };
    // Descend the higher node; at equal levels both: each child of a against the children of b.
    const bool descendA = p.levelA >= p.levelB && p.levelA > 0;
    const bool descendB = p.levelB >= p.levelA && p.levelB > 0;
    if (descendA && descendB) {
        unsigned maskA = a.childMask(p.levelA, p.nodeA, b.box(p.levelB, p.nodeB));
        const std::uint32_t levelA = p.levelA - 1;
        const std::uint32_t levelB = p.levelB - 1;
        while (maskA != 0) {
            const auto i = static_cast<std::uint32_t>(__builtin_ctz(maskA));
            maskA &= maskA - 1;
            const std::uint32_t childA = p.nodeA * kFanout + i;
            unsigned maskB = b.childMask(p.levelB, p.nodeB, a.box(levelA, childA));
            while (maskB != 0) {
                const auto j = static_cast<std::uint32_t>(__builtin_ctz(maskB));
                maskB &= maskB - 1;
                emit(levelA, childA, levelB, p.nodeB * kFanout + j);
            }
        }
    } else if (descendA) {
        unsigned mask = a.childMask(p.levelA, p.nodeA, b.box(p.levelB, p.nodeB));
        while (mask != 0) {
            const auto i = static_cast<std::uint32_t>(__builtin_ctz(mask));
            mask &= mask - 1;
            emit(p.levelA - 1, p.nodeA * kFanout + i, p.levelB, p.nodeB);
        }
    } else {
        unsigned mask = b.childMask(p.levelB, p.nodeB, a.box(p.levelA, p.nodeA));
        while (mask != 0) {
            const auto j = static_cast<std::uint32_t>(__builtin_ctz(mask));
            mask &= mask - 1;
            emit(p.levelA, p.nodeA, p.levelB - 1, p.nodeB * kFanout + j);
        }
    }
}

bool BoxTree::anyOverlap(const Aabb& query, std::vector<NodePair>& stack) const {
    if (empty()) return false;
    FloatBox q{};
    for (int k = 0; k < 3; ++k) {
        q.lo[k] = floatBelow(query.min[k]);
        q.hi[k] = floatAbove(query.max[k]);
    }
    if (!floatBoxesOverlap(box(m_levelCount - 1, 0), q)) return false;
    stack.clear();
    stack.push_back({m_levelCount - 1, 0, 0, 0});  // (level, node) in the A fields
    while (!stack.empty()) {
        const NodePair p = stack.back();
        stack.pop_back();
        if (p.levelA == 0) {
            if (m_leafBox[p.nodeA].overlaps(query)) return true;
            continue;
        }
        unsigned mask = childMask(p.levelA, p.nodeA, q);
        while (mask != 0) {
            const auto i = static_cast<std::uint32_t>(__builtin_ctz(mask));
            mask &= mask - 1;
            stack.push_back({p.levelA - 1, p.nodeA * kFanout + i, 0, 0});
        }
    }
    return false;
}

void BoxTree::split(const BoxTree& a, const BoxTree& b, std::size_t target, std::vector<NodePair>& out) {
    std::vector<std::vector<NodePair>> one;
    splitMany({{&a, &b, target}}, nullptr, one);
    out.swap(one[0]);
}

void BoxTree::splitMany(const std::vector<SplitJob>& jobs, TaskPool* pool, std::vector<std::vector<NodePair>>& out) {
    // All jobs' node pairs in one list, job by job; a round rewrites it.
    struct Entry {
        std::uint32_t job;
        NodePair pair;
    };
    // Working memory kept between calls (a frame's split is a few thousand entries; no allocation each frame),
    // this thread's: the workers below reach it through these references.
    struct Memory {
        std::vector<Entry> list, next;
        std::vector<std::vector<Entry>> chunkOut;  // a round's chunks: each chunk's own list, joined in order
        std::vector<std::size_t> count;             // node pairs per job
    };
    thread_local Memory memory;
    std::vector<Entry>& list = memory.list;
    std::vector<Entry>& next = memory.next;
    std::vector<std::vector<Entry>>& chunkOut = memory.chunkOut;
    std::vector<std::size_t>& count = memory.count;
    list.clear();
    count.assign(jobs.size(), 0);
    for (std::uint32_t j = 0; j < jobs.size(); ++j) {
        const BoxTree& a = *jobs[j].a;
        const BoxTree& b = *jobs[j].b;
        if (a.empty() || b.empty()) continue;
        const NodePair root{a.m_levelCount - 1, 0, b.m_levelCount - 1, 0};
        if (!floatBoxesOverlap(a.box(root.levelA, 0), b.box(root.levelB, 0))) continue;
        list.push_back({j, root});
        count[j] = 1;
    }
    constexpr std::size_t kChunk = 32;            // node pairs per chunk of a round
    constexpr std::size_t kParallelRound = 128;   // smaller rounds on this thread: a dispatch would cost more
    // A round descends every pair but leaf pairs of each job with fewer pairs than its target (count at the round's
    // start); the others are kept as they are.
    auto descends = [&](const Entry& e) {
        return !(e.pair.levelA == 0 && e.pair.levelB == 0) && count[e.job] < jobs[e.job].target;
    };
    auto expandRange = [&](std::size_t begin, std::size_t end, std::vector<Entry>& to) {
        thread_local std::vector<NodePair> children;
        for (std::size_t i = begin; i < end; ++i) {
            const Entry& e = list[i];
            if (!descends(e)) {
                to.push_back(e);
                continue;
            }
            children.clear();
            descend(*jobs[e.job].a, *jobs[e.job].b, e.pair, children, nullptr);
            for (const NodePair& c : children) to.push_back({e.job, c});
        }
    };
    for (;;) {
        if (std::none_of(list.begin(), list.end(), descends)) break;
        next.clear();
        const std::size_t chunks = (list.size() + kChunk - 1) / kChunk;
        if (list.size() < kParallelRound || pool == nullptr) {
            expandRange(0, list.size(), next);
        } else {
            if (chunkOut.size() < chunks) chunkOut.resize(chunks);
            pool->parallelFor(chunks, 1, [&](std::size_t begin, std::size_t end) {
                for (std::size_t c = begin; c < end; ++c) {
                    chunkOut[c].clear();
                    expandRange(c * kChunk, std::min(list.size(), (c + 1) * kChunk), chunkOut[c]);
                }
            });
            for (std::size_t c = 0; c < chunks; ++c) next.insert(next.end(), chunkOut[c].begin(), chunkOut[c].end());
        }
        std::fill(count.begin(), count.end(), 0);
        for (const Entry& e : next) ++count[e.job];
        list.swap(next);
    }
    if (out.size() < jobs.size()) out.resize(jobs.size());
    for (std::size_t j = 0; j < jobs.size(); ++j) out[j].clear();
    for (const Entry& e : list) out[e.job].push_back(e.pair);
}

void BoxTree::leafPairs(const BoxTree& a, const BoxTree& b, const NodePair& start, std::vector<NodePair>& stack,
                        std::vector<TrianglePair>& out) {
    if (start.levelA == 0 && start.levelB == 0) {
        if (a.leavesOverlap(start.nodeA, b, start.nodeB))
            out.push_back({a.m_leafTriangle[start.nodeA], b.m_leafTriangle[start.nodeB]});
        return;
    }
    stack.clear();
    stack.push_back(start);
    while (!stack.empty()) {
        const NodePair p = stack.back();
        stack.pop_back();
        descend(a, b, p, stack, &out);
    }
}

}  // namespace cullide
