#include "ReferenceVisibility.h"

#include "CullerBackends.h"
#include "DeviceExact.h"
#include "VisibilityLevel.h"
#include "bindings.h"

#include <algorithm>
#include <stdexcept>
#include <cmath>

// Every function below mirrors the GLSL function of the same name, operation for operation, in float (the library is
// built with -ffp-contract=off: no fused multiply-add here either). Literals are floats, as in GLSL.
namespace cullide {
namespace {

struct Vec2f {
    float x, y;
};

/// common.glsl Prim.
struct Prim {
    float rect[4];     ///< x0, y0, x1, y1 (pixels, undilated)
    float edge[3][3];  ///< (nx, ny, c): inside <= 0; (0, 0, -1) disables an edge
    float plane[4];    ///< (a, b, z0, valid)
    Vec2f origin;
    float zrange[2];
    int axis;
};

/// common.glsl project().
void project(const float p[3], int axis, const View& view, float out[3]) {
    const int ua = (axis + 1) % 3;
    const int va = (axis + 2) % 3;
    out[0] = (p[ua] - view.lo[ua]) * view.pixelScale[ua];
    out[1] = (p[va] - view.lo[va]) * view.pixelScale[va];
    out[2] = (p[axis] - view.lo[axis]) * view.depthScale[axis];
}

float dot2(Vec2f a, Vec2f b) { return a.x * b.x + a.y * b.y; }

/// common.glsl edgeFunction().
void edgeFunction(Vec2f from, Vec2f to, float s, float out[3]) {
    const Vec2f e{to.x - from.x, to.y - from.y};
    const Vec2f n{s * e.y, s * -e.x};
    out[0] = n.x;
    out[1] = n.y;
    out[2] = -dot2(n, from);
}

void disableEdges(Prim& p) {
    for (auto& e : p.edge) {
        e[0] = 0.0f;
        e[1] = 0.0f;
        e[2] = -1.0f;
    }
}

/// common.glsl makePrim() for a box primitive (box index `b` of the upload).
Prim makeBoxPrim(const GpuGeometry& g, std::uint32_t b, int axis, const View& view) {
    Prim p{};
    p.axis = axis;
    disableEdges(p);
    float lo[3], hi[3];
    project(&g.boxes[6 * std::size_t{b}], axis, view, lo);
    project(&g.boxes[6 * std::size_t{b} + 3], axis, view, hi);
    p.rect[0] = lo[0];
    p.rect[1] = lo[1];
    p.rect[2] = hi[0];
    p.rect[3] = hi[1];
    p.zrange[0] = lo[2];
    p.zrange[1] = hi[2];
    return p;
}

/// common.glsl makePrim() for triangle `t` of the upload.
Prim makeTrianglePrim(const GpuGeometry& g, std::uint32_t t, int axis, const View& view) {
    Prim p{};
    p.axis = axis;
    disableEdges(p);
    float q[3][3];
    for (std::size_t k = 0; k < 3; ++k) project(&g.positions[3 * std::size_t{g.indices[3 * std::size_t{t} + k]}], axis, view, q[k]);
    p.rect[0] = std::min(std::min(q[0][0], q[1][0]), q[2][0]);
    p.rect[1] = std::min(std::min(q[0][1], q[1][1]), q[2][1]);
    p.rect[2] = std::max(std::max(q[0][0], q[1][0]), q[2][0]);
    p.rect[3] = std::max(std::max(q[0][1], q[1][1]), q[2][1]);
    p.zrange[0] = std::min(std::min(q[0][2], q[1][2]), q[2][2]);
    p.zrange[1] = std::max(std::max(q[0][2], q[1][2]), q[2][2]);
    const Vec2f p0{q[0][0], q[0][1]}, p1{q[1][0], q[1][1]}, p2{q[2][0], q[2][1]};
    const Vec2f d1{p1.x - p0.x, p1.y - p0.y};
    const Vec2f d2{p2.x - p0.x, p2.y - p0.y};
    const float area2 = d1.x * d2.y - d1.y * d2.x;
    const Vec2f d3{p2.x - p1.x, p2.y - p1.y};
    const float maxEdge2 = std::max(std::max(dot2(d1, d1), dot2(d2, d2)), dot2(d3, d3));
    if (std::fabs(area2) > 1.0e-3f && std::fabs(area2) >= maxEdge2 * (1.0f / 256.0f)) {
        const float s = area2 > 0.0f ? 1.0f : -1.0f;
        edgeFunction(p0, p1, s, p.edge[0]);
        edgeFunction(p1, p2, s, p.edge[1]);
        edgeFunction(p2, p0, s, p.edge[2]);
        const float invArea = 1.0f / area2;
        const float pa = ((q[1][2] - q[0][2]) * d2.y - (q[2][2] - q[0][2]) * d1.y) * invArea;
        const float pb = ((q[2][2] - q[0][2]) * d1.x - (q[1][2] - q[0][2]) * d2.x) * invArea;
        p.plane[0] = pa;
        p.plane[1] = pb;
        p.plane[2] = q[0][2];
        p.plane[3] = 1.0f;
        p.origin = p0;
    }
    return p;
}

Prim makePrim(const GpuGeometry& g, std::uint32_t ref, int axis, const View& view) {
    if (ref & CULLIDE_PRIM_BOX_BIT) return makeBoxPrim(g, ref & ~CULLIDE_PRIM_BOX_BIT, axis, view);
    return makeTrianglePrim(g, ref, axis, view);
}

/// common.glsl edgeRejects().
bool edgeRejects(const float e[3], Vec2f c, Vec2f h) {
    return e[0] * c.x + e[1] * c.y + e[2] - (h.x * std::fabs(e[0]) + h.y * std::fabs(e[1])) > 0.0f;
}

/// common.glsl coverage(): whether the pixel square [c - h, c + h] meets the primitive, and its depth range there.
bool coverage(const Prim& p, Vec2f c, Vec2f h, bool conservative, const View& view, float& zlo, float& zhi) {
    zlo = 0.0f;
    zhi = 0.0f;
    if (c.x + h.x < p.rect[0] || c.x - h.x > p.rect[2] || c.y + h.y < p.rect[1] || c.y - h.y > p.rect[3]) return false;
    if (edgeRejects(p.edge[0], c, h) || edgeRejects(p.edge[1], c, h) || edgeRejects(p.edge[2], c, h)) return false;
    zlo = p.zrange[0];
    zhi = p.zrange[1];
    if (p.plane[3] != 0.0f) {
        const float zc = p.plane[2] + p.plane[0] * (c.x - p.origin.x) + p.plane[1] * (c.y - p.origin.y);
        const float r = h.x * std::fabs(p.plane[0]) + h.y * std::fabs(p.plane[1]);
        const float lo = std::max(zc - r, zlo);
        const float hi = std::min(zc + r, zhi);
        if (lo <= hi) {
            zlo = lo;
            zhi = hi;
        } else if (!conservative) {
            zlo = std::clamp(zc, p.zrange[0], p.zrange[1]);
            zhi = zlo;
        }
    }
    if (conservative) {
        const float pad = view.depthPad[p.axis] + (p.zrange[1] - p.zrange[0]) * (1.0f / 4096.0f);
        zlo -= pad;
        zhi += pad;
    }
    return true;
}

/// A float pixel bound as scan.glsl's int conversion sees it, clamped first so that the conversion is defined (the
/// clamp changes nothing after scan.glsl's own clamp to [0, resolution - 1]).
int pixelIndex(float v, int resolution) {
    return static_cast<int>(std::clamp(v, -1.0f, static_cast<float>(resolution)));
}

/// scan.glsl's scan: calls visit(pixelX, pixelY, zlo, zhi) for every pixel centre whose square meets the primitive.
template <typename Visit>
void forEachFragment(const Prim& p, Vec2f h, bool conservative, const View& view, int resolution, Visit&& visit) {
    const int firstX = std::max(pixelIndex(std::floor(p.rect[0] - h.x - 0.5f), resolution), 0);
    const int firstY = std::max(pixelIndex(std::floor(p.rect[1] - h.y - 0.5f), resolution), 0);
    const int lastX = std::min(pixelIndex(std::ceil(p.rect[2] + h.x - 0.5f), resolution), resolution - 1);
    const int lastY = std::min(pixelIndex(std::ceil(p.rect[3] + h.y - 0.5f), resolution), resolution - 1);
    for (int y = firstY; y <= lastY; ++y) {
        for (int x = firstX; x <= lastX; ++x) {
            const Vec2f c{static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f};
            float zlo = 0.0f, zhi = 0.0f;
            if (coverage(p, c, h, conservative, view, zlo, zhi))
                visit(static_cast<std::size_t>(y) * static_cast<std::size_t>(resolution) + static_cast<std::size_t>(x), zlo, zhi);
        }
    }
}

/// visit.glsl quantizeDown() / quantizeUp().
std::uint32_t quantizeDown(float z, float maxQ) {
    return static_cast<std::uint32_t>(std::floor(std::clamp(z, 0.0f, 1.0f) * maxQ));
}
std::uint32_t quantizeUp(float z, float maxQ) {
    return static_cast<std::uint32_t>(std::ceil(std::clamp(z, 0.0f, 1.0f) * maxQ));
}

}  // namespace

ReferenceVisibility::ReferenceVisibility(const Settings& settings) : m_settings(settings) {}

void ReferenceVisibility::upload(const GpuGeometry& geometry, Stats&) {
    m_geometry = &geometry;
    if (geometry.mapped.empty() && geometry.builtRanges.empty()) return;
    // With the mapped meshes' vertices mapped and the built boxes built here, as the GL backend does on the device.
    m_mapped = geometry;
    m_mapped.positions = allPositions(geometry);
    m_mapped.mapped.clear();
    m_mapped.boxes = allBoxes(geometry, m_mapped.positions);
    m_mapped.builtRanges.clear();
    m_geometry = &m_mapped;
}

void ReferenceVisibility::pruneLevel(const LevelItems& items, const LevelStart& start,
                                     std::vector<std::uint8_t>& survivors, LevelStats& level, Stats& stats,
                                     std::vector<IterationTrace>* trace) {
    m_items = &items;
    View view = start.view;
    std::uint32_t idBits = start.idBits;
    if (items.describedByObjects()) {
        if (items.inheritsParents) m_parentAlive.swap(m_alive);
        startByObjects(items, start.coordinateBound, view, idBits);
        m_items = &m_expanded;
    } else {
        m_alive.assign(items.size(), 1);
    }
    std::size_t alive = static_cast<std::size_t>(std::count(m_alive.begin(), m_alive.end(), 1));
    if (!level.itemsPerIteration.empty()) level.itemsPerIteration.front() = alive;  // those that start alive
    for (int iteration = 0;; ++iteration) {
        const IterationResult r = iterate(view, idBits, level, stats);
        if (trace) trace->push_back({view, idBits, r});
        const Step step = stepAfter(r, alive, iteration, m_settings);
        noteIteration(level, alive, r.alive, step);
        if (step == Step::AllPruned) std::fill(m_alive.begin(), m_alive.end(), 0);
        if (step != Step::Next) break;
        alive = r.alive;
        view = fitView(r.bounds, m_settings, start.coordinateBound);
        idBits = idBitsFor(r.ownerMax);
    }
    survivors = m_alive;
}

namespace {

/// start.comp meets(): whether `item` (float bounds, as deviceBoundsOf gives them) meets box `box` grown by `slack` on
/// each side, in float.
bool meetsGrown(const Aabb& item, const float* box, float slack) {
    for (int a = 0; a < 3; ++a) {
        const float boxLo = box[a] - slack;
        const float boxHi = box[3 + a] + slack;
        if (!(static_cast<float>(item.min[a]) <= boxHi && boxLo <= static_cast<float>(item.max[a]))) return false;
    }
    return true;
}

}  // namespace

void ReferenceVisibility::startByObjects(const LevelItems& items, double coordinateBound, View& view,
                                         std::uint32_t& idBits) {
    const GpuGeometry& g = *m_geometry;
    const std::size_t n = items.size();
    m_expanded.clear();
    m_expanded.owner.resize(n);
    m_expanded.prims.resize(n);
    m_expanded.primBegin.resize(n + 1);
    for (std::size_t i = 0; i <= n; ++i) m_expanded.primBegin[i] = static_cast<std::uint32_t>(i);
    m_alive.assign(n, 0);
    Aabb bounds;
    std::uint32_t ownerMax = 0;
    for (const ObjectRange& r : items.objectRanges) {
        const bool isBox = (r.kind & 1u) == CULLIDE_RANGE_BOXES;
        for (std::uint32_t j = 0; j < r.count; ++j) {
            const std::size_t i = std::size_t{r.itemBegin} + j;
            const std::uint32_t prim = isBox ? (r.first + j) | CULLIDE_PRIM_BOX_BIT : g.ordered.at(r.first + j);
            m_expanded.prims.at(i) = prim;
            m_expanded.owner.at(i) = r.owner;
            const std::uint32_t parent = r.parent + (isBox ? j : j / items.groupSize);
            bool live = !items.inheritsParents || m_parentAlive.at(parent) != 0;
            const Aabb box = deviceBoundsOf(g, m_expanded, i);
            if (live && (r.kind & CULLIDE_RANGE_KEEP) == 0) {
                bool kept = false;
                for (std::uint32_t p = r.partnerBegin; p < r.partnerEnd && !kept; ++p)
                    kept = meetsGrown(box, &g.boxes.at(6 * std::size_t{items.partnerBoxes.at(p)}), items.prepassSlack);
                live = kept;
            }
            if (!live) continue;
            m_alive[i] = 1;
            bounds.grow(box);
            ownerMax = std::max(ownerMax, r.owner);
        }
    }
    if (bounds.isEmpty()) bounds = Aabb{Vec3::Zero(), Vec3::Zero()};  // none alive: the view of the origin
    view = fitView(bounds, m_settings, coordinateBound);
    idBits = idBitsFor(ownerMax);
}

void ReferenceVisibility::pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex,
                                          Stats& stats, std::vector<IterationTrace>* trace) {
    std::vector<std::uint8_t> survivors;
    pruneLevel(items, start, survivors, stats.levels.at(levelIndex), stats, trace);
}

void ReferenceVisibility::pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex,
                                             Stats& stats, std::vector<IterationTrace>* trace) {
    DeferredLevel level;
    level.complete = true;
    pruneLevel(items, start, level.survivors, stats.levels.at(levelIndex), stats, trace);
    if (items.exact.run && items.describedByObjects()) {
        findExactPairs(m_geometry->positions, m_geometry->indices, items, m_expanded.prims, level.survivors,
                       level.exactPairs);
        level.exactRan = true;
    }
    m_deferred.push_back(std::move(level));
}

bool ReferenceVisibility::collect(const Deadline&, std::vector<DeferredLevel>& results, Stats&) {
    results.swap(m_deferred);
    m_deferred.clear();
    return true;
}

IterationResult ReferenceVisibility::iterate(const View& view, std::uint32_t idBits, LevelStats& level,
                                             Stats& stats) {
    const LevelItems& items = *m_items;
    const GpuGeometry& geometry = *m_geometry;
    const int res = m_settings.resolution;
    const bool conservative = m_settings.mode == Mode::Reliable;
    const float maxQ = static_cast<float>((1u << depthBitsFor(idBits)) - 2u);
    const std::uint32_t idMask = (1u << idBits) - 1u;
    const std::size_t pixels = static_cast<std::size_t>(res) * static_cast<std::size_t>(res);
    m_flags.assign(items.size(), 0);
    for (int axis = 0; axis < 3; ++axis) {
        if ((m_settings.axes & (1u << axis)) == 0) continue;
        const Vec2f h = conservative ? Vec2f{view.halfSize[(axis + 1) % 3], view.halfSize[(axis + 2) % 3]}
                                     : Vec2f{0.0f, 0.0f};
        m_near1.assign(pixels, 0xFFFFFFFFu);
        m_near2.assign(pixels, 0xFFFFFFFFu);
        m_far1.assign(pixels, 0u);
        m_far2.assign(pixels, 0u);
        // visit.glsl visit(), pass by pass over every alive item's primitives.
        for (int pass = CULLIDE_PASS_NEAREST; pass <= CULLIDE_PASS_FLAG; ++pass) {
            for (std::size_t i = 0; i < items.size(); ++i) {
                if (!m_alive[i]) continue;
                const std::uint32_t owner = items.owner[i];
                for (std::uint32_t k = items.primBegin[i]; k < items.primBegin[i + 1]; ++k) {
                    const Prim p = makePrim(geometry, items.prims[k], axis, view);
                    forEachFragment(p, h, conservative, view, res, [&](std::size_t px, float zlo, float zhi) {
                        const std::uint32_t qlo = quantizeDown(zlo, maxQ);
                        const std::uint32_t qhi = quantizeUp(zhi, maxQ);
                        const std::uint32_t nearValue = (qlo << idBits) | owner;
                        const std::uint32_t farValue = ((qhi + 1u) << idBits) | owner;
                        if (pass == CULLIDE_PASS_NEAREST) {
                            m_near1[px] = std::min(m_near1[px], nearValue);
                            m_far1[px] = std::max(m_far1[px], farValue);
                            return;
                        }
                        const std::uint32_t n1 = m_near1[px];
                        const std::uint32_t f1 = m_far1[px];
                        if (pass == CULLIDE_PASS_SECOND) {
                            if ((n1 & idMask) != owner) m_near2[px] = std::min(m_near2[px], nearValue);
                            if ((f1 & idMask) != owner) m_far2[px] = std::max(m_far2[px], farValue);
                            return;
                        }
                        const std::uint32_t nearOther = (n1 & idMask) == owner ? m_near2[px] : n1;
                        const std::uint32_t farOther = (f1 & idMask) == owner ? m_far2[px] : f1;
                        if (nearOther != 0xFFFFFFFFu && qhi >= (nearOther >> idBits))
                            m_flags[i] |= 1u << (2 * axis);
                        if (farOther != 0u && qlo + 1u <= (farOther >> idBits)) m_flags[i] |= 1u << (2 * axis + 1);
                    });
                }
                if (pass == CULLIDE_PASS_NEAREST) level.primitivesDrawn += items.primBegin[i + 1] - items.primBegin[i];
            }
        }
    }
    level.draws += 3;
    stats.draws += 3;
    // survive.comp: an alive item not hidden in every enabled view leaves the set.
    const std::uint32_t required = requiredFlags(m_settings.axes);
    IterationResult r;
    r.ownerMin = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (!m_alive[i]) continue;
        if ((m_flags[i] & required) != required) {
            m_alive[i] = 0;
            continue;
        }
        ++r.alive;
        r.ownerMin = std::min(r.ownerMin, items.owner[i]);
        r.ownerMax = std::max(r.ownerMax, items.owner[i]);
        r.bounds.grow(deviceBoundsOf(*m_geometry, items, i));
    }
    return r;
}


std::unique_ptr<PruningBackend> createReferencePruningBackend(const Settings& settings) {
    return std::make_unique<ReferenceVisibility>(settings);
}

std::unique_ptr<Culler> createVisibilityReferenceCuller(const Settings& settings) {
    return createGpuCuller(settings, createReferencePruningBackend);
}

}  // namespace cullide
