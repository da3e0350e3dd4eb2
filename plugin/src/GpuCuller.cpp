// CULLIDE: object, sub-object (group) and triangle levels of image-space visibility pruning, then the exact stage.
#include "AutoLevels.h"
#include "CullerBackends.h"
#include "ExactStage.h"
#include "FloatRounding.h"
#include "FrameObjects.h"
#include "Morton.h"
#include "WorldMeshes.h"
#include "cullide/Timer.h"
#include "bindings.h"
#include "cullide/Culler.h"
#include "VisibilityLevel.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace cullide {
namespace {

/// The one-line notice that a culler runs without GL: once per process and reason, not for every culler (the Bullet
/// adapter re-creates its culler when its margin must grow).
void noticeOnce(const std::string& reason) {
    static std::mutex mutex;
    static std::set<std::string> given;
    const std::lock_guard<std::mutex> lock(mutex);
    if (given.insert(reason).second)
        std::fprintf(stderr, "cullide: no usable GL device, running the CPU path (no GPU levels): %s\n", reason.c_str());
}

struct Group {
    std::uint32_t object;
    std::uint32_t first;  ///< into the object's spatial triangle order
    std::uint32_t count;
    Aabb box;  ///< world, inflated by margin / 2
};

class GpuCuller final : public Culler {
public:
    GpuCuller(const Settings& settings, const PruningBackendFactory& makeBackend)
        : m_settings(settings), m_pool(settings.threads), m_exact(m_pool) {
        openBackend(makeBackend);
    }

    const Settings& settings() const override { return m_settings; }

    void run(const std::vector<Object>& objects, Result& result) override { runFrame(objects, nullptr, result); }

    void run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& only, Result& result) override {
        checkPairList(only, objects.size());
        runFrame(objects, &only, result);
    }

private:
    /// One frame: every overlapping pair, or only those listed in `only`.
    void runFrame(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>* only, Result& result) {
        Timer total;
        result.clear();
        Stats& stats = result.stats;
        stats.renderer = m_backend ? m_backend->renderer() : std::string();
        stats.device = m_backend ? m_backend->device() : std::string("none");
        stats.gpuUnavailable = m_gpuUnavailable;
        const double margin = m_settings.margin;
        m_objects = &objects;

        // CPU box pre-pass over objects.
        Timer prepass;
        lookUpStatics(objects);
        m_valid = validateObjects(objects, margin, result.rejected, &m_pool, &m_known);
        mergeStatics(result, stats);
        stats.objects = objects.size();
        stats.rejectedObjects = result.rejected.size();
        for (std::size_t i = 0; i < objects.size(); ++i) {
            if (m_valid[i].valid && m_valid[i].isMesh) stats.triangles += objects[i].mesh->triangles.size();
            if (m_valid[i].valid) ++stats.prepassObjectsIn;
        }
        const bool paper = m_settings.pipeline == Pipeline::Paper;
        m_pairs = only != nullptr ? listedOverlappingPairs(m_valid, *only) : overlappingPairs(m_valid);
        m_partners.assign(objects.size(), {});
        for (const auto& [a, b] : m_pairs) {
            m_partners[a].push_back(b);
            m_partners[b].push_back(a);
        }
        m_active.assign(objects.size(), 0);
        for (std::size_t i = 0; i < objects.size(); ++i) {
            // Only objects whose box meets another's can collide (both pipelines): the views are fitted to the
            // groups that can meet (clusters, runLevels), never to a far outlier.
            const bool participates = !m_partners[i].empty();
            m_active[i] = participates ? 1 : 0;
            stats.prepassObjectsOut += m_active[i];
        }
        m_objects = &m_world.resolve(objects, m_active, &m_pool);  // world-space meshes of the kept objects
        m_survivingTriangles.assign(objects.size(), {});
        m_autoActive = false;
        m_gpuLevels = m_backend != nullptr && chooseGpuLevels(paper, stats);
        buildGroups(!paper, stats);
        stats.prepassMs = prepass.ms();

        m_uploaded = false;
        Timer levels;
        try {
            runLevels(paper, stats);
        } catch (const BackendError& e) {
            // A GL error mid-frame costs this frame its GPU pruning, never a contact: every triangle that the CPU
            // pre-pass keeps goes to the exact stage.
            ++stats.gpuFallbacks;
            stats.gpuError = e.what();
            if (m_backend) m_backend->forgetUploads();  // what the device holds is no longer trusted
            m_survivingTriangles.assign(m_valid.size(), {});
            collectTriangles(m_groups, !paper);
            finishFromTriangles({});
        }
        // Without GPU levels this stage is the CPU collection of the pre-pass's triangles: count it there.
        if (m_gpuLevels)
            stats.gpuLevelsMs = levels.ms() - stats.uploadMs;
        else
            stats.prepassMs += levels.ms() - stats.uploadMs;

        Timer exact;
        assemblePairs(result);
        stats.exactMs = exact.ms();
        stats.pcsObjects = result.pcs.size();
        stats.candidateObjectPairs = result.pairs.size();
        result.pcsTriangles.swap(m_survivingTriangles);  // reassigned at the start of the next frame
        stats.gpuDeviceBytes = m_backend ? m_backend->deviceBytes() : 0;
        stats.totalMs = total.ms();
        if (m_autoActive) recordAutoFrame(stats);
        m_objects = nullptr;
    }

    /// Whether this frame runs the GPU levels (a GL device is there): always in the paper pipeline and with
    /// GpuLevels::Always; with GpuLevels::Auto, as AutoLevels decides from timing both paths on this scene.
    bool chooseGpuLevels(bool paper, Stats& stats) {
        m_autoActive = !paper && m_settings.gpuLevels == GpuLevels::Auto;
        if (!m_autoActive) return paper || m_settings.gpuLevels == GpuLevels::Always;
        std::size_t triangles = 0;
        for (std::size_t i = 0; i < m_active.size(); ++i)
            if (m_active[i] && m_valid[i].isMesh) triangles += (*m_objects)[i].mesh->triangles.size();
        m_autoPath = m_auto.choose(triangles);
        stats.autoDecision = m_auto.decision();
        return m_autoPath == AutoLevels::Path::Gpu;
    }

    /// A frame that fell back to the CPU path after a GL error is no timing of the GPU levels: not recorded.
    void recordAutoFrame(Stats& stats) {
        if (stats.gpuFallbacks == 0) m_auto.record(m_autoPath, stats.totalMs);
        stats.autoDecision = m_auto.decision();
        stats.autoCpuMs = m_auto.cpuMs();
        stats.autoGpuMs = m_auto.gpuMs();
    }

    /// The pruning backend (the GL visibility pass in production), unless GPU levels are off (GpuLevels::Never: no
    /// EGL at all). Without a usable GL device the CPU path runs instead, with a one-line notice — unless GPU levels
    /// were demanded (GpuLevels::Always, Pipeline::Paper): then GlUnavailableError.
    void openBackend(const PruningBackendFactory& makeBackend) {
        if (m_settings.gpuLevels == GpuLevels::Never) {
            m_gpuUnavailable = "GPU levels off (GpuLevels::Never): no GL context opened";
            return;
        }
        try {
            m_backend = makeBackend(m_settings);
        } catch (const GlUnavailableError& e) {
            const bool demanded = m_settings.gpuLevels == GpuLevels::Always || m_settings.pipeline == Pipeline::Paper;
            if (demanded) throw;
            m_backend.reset();
            m_gpuUnavailable = e.what();
            noticeOnce(m_gpuUnavailable);
        }
    }

    /// What the culler keeps of a static mesh (Object::staticKey) between frames: its validation and its triangle
    /// boxes, valid while (version, vertex count, triangle count) stay the same.
    struct StaticEntry {
        std::uint64_t version = 0;
        std::size_t vertices = 0;
        std::size_t triangles = 0;
        bool transformed = false;
        Transform transform;  ///< when transformed: the one the cached world boxes were built with
        bool checked = false;
        ValidatedObject valid;
        std::string error;  ///< the rejection message, if it was rejected
        bool boxesReady = false;
        std::vector<Aabb> boxes;
        std::uint64_t lastFrame = 0;
        std::uint64_t regionEpoch = 0;  ///< == m_regionEpoch: its triangles are in the device's resident region
        std::uint32_t regionBaseTriangle = 0;
    };
    /// Entries unused for this many frames are dropped (a static object far from every moving one is not handed
    /// to the culler by the adapter; it comes back when something approaches).
    static constexpr std::uint64_t kStaticKeepFrames = 240;

    void lookUpStatics(const std::vector<Object>& objects) {
        ++m_frame;
        for (auto it = m_static.begin(); it != m_static.end();)
            it = it->second.lastFrame + kStaticKeepFrames < m_frame ? m_static.erase(it) : std::next(it);
        m_staticEntry.assign(objects.size(), nullptr);
        m_known.assign(objects.size(), 0);
        for (std::size_t i = 0; i < objects.size(); ++i) {
            const Object& o = objects[i];
            if (o.mesh == nullptr || o.staticKey == 0) continue;
            StaticEntry& e = m_static[o.staticKey];
            if (e.lastFrame == m_frame) continue;  // a key used twice in one frame: the second is not cached
            if (!e.checked || e.version != o.version || e.vertices != o.mesh->vertices.size() ||
                e.triangles != o.mesh->triangles.size() || !sameTransform(e, o.transform)) {
                e = StaticEntry{};
                e.version = o.version;
                e.vertices = o.mesh->vertices.size();
                e.triangles = o.mesh->triangles.size();
                e.transformed = o.transform != nullptr;
                if (e.transformed) e.transform = *o.transform;
            }
            e.lastFrame = m_frame;
            m_staticEntry[i] = &e;
            m_known[i] = e.checked ? 1 : 0;
        }
    }

    /// The cached world boxes of a static entry hold for this object's transform (bit for bit; NaNs never match).
    static bool sameTransform(const StaticEntry& e, const Transform* t) {
        if (t == nullptr) return !e.transformed;
        return e.transformed && e.transform.linear == t->linear && e.transform.translation == t->translation;
    }

    /// Validation results of statics: kept ones into this frame, new ones into the cache.
    void mergeStatics(Result& result, Stats& stats) {
        bool added = false;
        for (std::size_t i = 0; i < m_staticEntry.size(); ++i) {
            StaticEntry* e = m_staticEntry[i];
            if (e == nullptr) continue;
            const auto id = static_cast<std::uint32_t>(i);
            if (m_known[i]) {
                m_valid[i] = e->valid;
                if (!e->error.empty()) {
                    result.rejected.push_back({id, e->error});
                    added = true;
                }
                ++stats.staticObjectsReused;
                continue;
            }
            e->checked = true;
            e->valid = m_valid[i];
            for (const ObjectDiagnostic& d : result.rejected)
                if (d.object == id) e->error = d.message;
        }
        if (added)
            std::stable_sort(result.rejected.begin(), result.rejected.end(),
                             [](const ObjectDiagnostic& a, const ObjectDiagnostic& b) { return a.object < b.object; });
    }

    const TriangleMesh& meshOf(std::uint32_t o) const { return *(*m_objects)[o].mesh; }
    bool isMesh(std::uint32_t o) const { return m_valid[o].isMesh; }

    Aabb relative(const Aabb& b) const { return {b.min - m_origin, b.max - m_origin}; }

    /// Orders an object's triangles along a Morton curve of their centroids, so that k consecutive ones are close
    /// together whatever the file order (scanned meshes and soups are not stored spatially). Per frame, O(n).
    void spatialOrder(std::uint32_t o, std::vector<std::uint32_t>& order) const {
        thread_local std::vector<std::uint64_t> keys;  // per worker: objects are ordered in parallel
        thread_local std::vector<std::uint64_t> tmp;
        const TriangleMesh& mesh = meshOf(o);
        const Aabb& box = m_valid[o].box;
        const Vec3 scale = (box.extent().array().max(1e-300)).inverse() * 1023.0;
        keys.clear();
        for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
            const auto& tri = mesh.triangles[t];
            const Vec3 c = ((mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0 - box.min)
                               .cwiseProduct(scale);
            keys.push_back(morton::key(morton::code(c[0], c[1], c[2]), t));
        }
        morton::sortByCode(keys, tmp);
        order.resize(keys.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(keys[i]);
    }

    /// Triangle boxes of new static meshes; with GPU levels also every active mesh's boxes, its spatial order and
    /// its groups of k spatially consecutive triangles (with `prepass`, only groups whose box overlaps a partner
    /// object's box are kept). Without GPU levels the rest happens in collectDirect.
    void buildGroups(bool prepass, Stats& stats) {
        m_groups.clear();
        m_order.resize(m_valid.size());
        m_triangleBoxes.resize(m_valid.size());
        m_boxesOf.assign(m_valid.size(), nullptr);
        m_needBoxes.assign(m_valid.size(), 0);
        const auto k = static_cast<std::uint32_t>(m_settings.groupSize);
        if (m_gpuLevels) {  // the CPU path has no groups (collectDirect)
            m_pool.parallelFor(m_valid.size(), 1, [&](std::size_t begin, std::size_t end) {
                for (std::size_t o = begin; o < end; ++o)
                    if (m_active[o] && isMesh(static_cast<std::uint32_t>(o)))
                        spatialOrder(static_cast<std::uint32_t>(o), m_order[o]);
            });
        }
        for (std::uint32_t o = 0; o < m_valid.size(); ++o) {
            if (!m_active[o] || !isMesh(o)) continue;
            const TriangleMesh& mesh = meshOf(o);
            StaticEntry* e = m_staticEntry[o];
            if (e != nullptr) {
                m_boxesOf[o] = &e->boxes;
                if (e->boxesReady) continue;
                e->boxes.resize(mesh.triangles.size());
                e->boxesReady = true;  // filled below
            } else {
                m_triangleBoxes[o].resize(mesh.triangles.size());
                m_boxesOf[o] = &m_triangleBoxes[o];
                if (!m_gpuLevels) continue;
            }
            m_needBoxes[o] = 1;
        }
        // New static meshes' triangle boxes (and, with GPU levels, every other active mesh's), in ranges on every
        // worker; without GPU levels the other meshes' boxes are computed where they are filtered (collectDirect).
        constexpr std::uint32_t kRange = 8192;
        m_ranges.clear();
        for (std::uint32_t o = 0; o < m_valid.size(); ++o) {
            if (!m_needBoxes[o]) continue;
            const auto n = static_cast<std::uint32_t>(meshOf(o).triangles.size());
            for (std::uint32_t first = 0; first < n; first += kRange)
                m_ranges.push_back({o, first, std::min(n, first + kRange)});
        }
        const double inflate = 0.5 * m_settings.margin;
        m_pool.parallelFor(m_ranges.size(), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t r = begin; r < end; ++r) {
                const Range& range = m_ranges[r];
                const TriangleMesh& mesh = meshOf(range.object);
                std::vector<Aabb>& boxes = *m_boxesOf[range.object];
                for (std::uint32_t t = range.begin; t < range.end; ++t) boxes[t] = triangleBounds(mesh, t, inflate);
            }
        });
        if (!m_gpuLevels) return;  // groups only feed GPU levels: collectDirect filters triangles itself
        m_groupCandidates.clear();
        for (std::uint32_t o = 0; o < m_valid.size(); ++o) {
            if (!m_active[o] || !isMesh(o)) continue;
            const auto n = static_cast<std::uint32_t>(meshOf(o).triangles.size());
            for (std::uint32_t first = 0; first < n; first += k)
                m_groupCandidates.push_back({o, first, std::min(k, n - first), {}});
        }
        m_groupKept.resize(m_groupCandidates.size());
        m_pool.parallelFor(m_groupCandidates.size(), 256, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                Group& g = m_groupCandidates[i];
                const std::vector<Aabb>& boxes = *m_boxesOf[g.object];
                const std::vector<std::uint32_t>& order = m_order[g.object];
                for (std::uint32_t t = g.first; t < g.first + g.count; ++t) g.box.grow(boxes[order[t]]);
                m_groupKept[i] = !prepass || overlapsPartner(g.object, g.box);
            }
        });
        stats.prepassGroupsIn += m_groupCandidates.size();
        for (std::size_t i = 0; i < m_groupCandidates.size(); ++i)
            if (m_groupKept[i]) m_groups.push_back(m_groupCandidates[i]);
        stats.prepassGroupsOut = m_groups.size();
    }

    bool overlapsPartner(std::uint32_t o, const Aabb& box) const {
        for (std::uint32_t p : m_partners[o])
            if (box.overlaps(m_valid[p].box)) return true;
        return false;
    }

    /// Positions and indices of active meshes, boxes of active objects and of the kept groups, relative to an
    /// origin near the centre of the active objects (float precision is spent on the scene, not on its offset).
    /// Static meshes (Object::staticKey) sit in a resident region at the front of the position and index buffers
    /// and are sent to the device once: the region and its origin are kept while the active objects stay near the
    /// origin (within half the region's extent, between a quarter and twice as large) and no more than half of it
    /// is stale.
    void uploadGeometry(Stats& stats) {
        Aabb all;
        std::size_t activeStaticTriangles = 0;
        for (std::uint32_t o = 0; o < m_valid.size(); ++o) {
            if (!m_active[o]) continue;
            all.grow(m_valid[o].box);
            if (isMesh(o) && m_staticEntry[o] != nullptr) activeStaticTriangles += meshOf(o).triangles.size();
        }
        const Vec3 centre = all.isEmpty() ? Vec3::Zero() : Vec3(0.5 * (all.min + all.max));
        const double extent = all.isEmpty() ? 0.0 : all.extent().maxCoeff();
        const bool keepRegion = m_regionEpoch != 0 &&
                                (centre - m_origin).cwiseAbs().maxCoeff() <= 0.5 * m_regionExtent &&
                                extent <= 2.0 * m_regionExtent && extent >= 0.25 * m_regionExtent &&
                                m_regionTriangles <= 2 * activeStaticTriangles + 65536;
        if (!keepRegion) {
            ++m_regionEpoch;
            m_origin = centre;
            m_regionExtent = std::max(extent, 1e-300);
            m_regionVertices = 0;
            m_regionTriangles = 0;
        }
        m_geometry.positions.resize(3 * m_regionVertices);
        m_geometry.indices.resize(3 * m_regionTriangles);
        m_geometry.keptPositions = m_geometry.positions.size();
        m_geometry.keptIndices = m_geometry.indices.size();
        m_geometry.boxes.clear();
        m_baseTriangle.assign(m_valid.size(), 0);
        m_objectBox.assign(m_valid.size(), 0);
        // Static meshes: in the region already, or appended to it now (sent this frame, kept afterwards).
        m_appended.clear();
        std::size_t vertices = m_regionVertices;
        std::size_t triangles = m_regionTriangles;
        auto append = [&](std::uint32_t o) {
            m_appended.push_back({o, static_cast<std::uint32_t>(vertices), static_cast<std::uint32_t>(triangles)});
            m_baseTriangle[o] = static_cast<std::uint32_t>(triangles);
            vertices += meshOf(o).vertices.size();
            triangles += meshOf(o).triangles.size();
        };
        for (std::uint32_t o = 0; o < m_valid.size(); ++o) {
            StaticEntry* e = m_staticEntry[o];
            if (!m_active[o] || !isMesh(o) || e == nullptr) continue;
            if (e->regionEpoch != m_regionEpoch) {
                append(o);
                e->regionEpoch = m_regionEpoch;
                e->regionBaseTriangle = m_baseTriangle[o];
            }
            m_baseTriangle[o] = e->regionBaseTriangle;
        }
        m_regionVertices = vertices;
        m_regionTriangles = triangles;
        // Everything else, every frame.
        for (std::uint32_t o = 0; o < m_valid.size(); ++o)
            if (m_active[o] && isMesh(o) && m_staticEntry[o] == nullptr) append(o);
        m_geometry.positions.resize(3 * vertices);
        m_geometry.indices.resize(3 * triangles);
        m_pool.parallelFor(m_appended.size(), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) writeMesh(m_appended[i]);
        });
        double bound = 0.0;
        for (std::uint32_t o = 0; o < m_valid.size(); ++o)
            if (m_active[o]) m_objectBox[o] = appendBox(m_valid[o].box, bound);
        m_groupBox.resize(m_groups.size());
        for (std::size_t g = 0; g < m_groups.size(); ++g) m_groupBox[g] = appendBox(m_groups[g].box, bound);
        m_geometry.coordinateBound = bound;
        m_backend->upload(m_geometry, stats);
    }

    /// Where a mesh goes in the frame's position and index arrays.
    struct MeshSlot {
        std::uint32_t object;
        std::uint32_t baseVertex;
        std::uint32_t baseTriangle;
    };

    /// A mesh's vertices (relative to the origin, as floats) and its triangles' global vertex indices.
    void writeMesh(const MeshSlot& slot) {
        const TriangleMesh& mesh = meshOf(slot.object);
        float* position = &m_geometry.positions[3 * std::size_t{slot.baseVertex}];
        for (const Vec3& v : mesh.vertices) {
            const Vec3 r = v.allFinite() ? Vec3(v - m_origin) : Vec3::Zero();  // unused vertices may be NaN
            for (int a = 0; a < 3; ++a) *position++ = static_cast<float>(r[a]);
        }
        std::uint32_t* index = &m_geometry.indices[3 * std::size_t{slot.baseTriangle}];
        for (const auto& t : mesh.triangles)
            for (std::uint32_t k : t) *index++ = slot.baseVertex + k;
    }

    std::uint32_t appendBox(const Aabb& worldBox, double& bound) {
        const Aabb r = relative(worldBox);
        for (int a = 0; a < 3; ++a) m_geometry.boxes.push_back(floatDown(r.min[a]));
        for (int a = 0; a < 3; ++a) m_geometry.boxes.push_back(floatUp(r.max[a]));
        bound = std::max({bound, r.min.cwiseAbs().maxCoeff(), r.max.cwiseAbs().maxCoeff()});
        return static_cast<std::uint32_t>(m_geometry.boxes.size() / 6 - 1);
    }

    /// Compact owner ids for the objects present in a level.
    std::uint32_t ownerOf(std::uint32_t object) {
        auto& id = m_ownerId[object];
        if (id == kNoOwner) id = m_ownerCount++;
        return id;
    }
    /// Starts building a level's items. The frame's geometry goes to the GPU only when a level actually runs.
    void beginLevel(Stats& stats) {
        if (!m_uploaded) {
            Timer upload;
            uploadGeometry(stats);
            stats.uploadMs += upload.ms();
            m_uploaded = true;
        }
        m_ownerId.assign(m_valid.size(), kNoOwner);
        m_ownerCount = 0;
        m_items.clear();
    }

    void addBoxItem(std::uint32_t object, std::uint32_t box, const Aabb& worldBox) {
        m_items.owner.push_back(ownerOf(object));
        m_items.prims.push_back(box | CULLIDE_PRIM_BOX_BIT);
        m_items.primBegin.push_back(static_cast<std::uint32_t>(m_items.prims.size()));
        m_items.bounds.push_back(relative(worldBox));
    }
    void addTriangleItem(std::uint32_t object, const std::uint32_t* triangles, std::uint32_t count, const Aabb& worldBox) {
        m_items.owner.push_back(ownerOf(object));
        for (std::uint32_t i = 0; i < count; ++i) m_items.prims.push_back(m_baseTriangle[object] + triangles[i]);
        m_items.primBegin.push_back(static_cast<std::uint32_t>(m_items.prims.size()));
        m_items.bounds.push_back(relative(worldBox));
    }

    void pruneLevel(const char* name, Stats& stats) {
        stats.levels.push_back(LevelStats{});
        LevelStats& level = stats.levels.back();
        level.name = name;
        cullide::pruneLevel(*m_backend, m_items, m_settings, m_geometry.coordinateBound, m_survivors, level, stats);
    }

    struct Tri {
        std::uint32_t object;
        std::uint32_t triangle;
    };

    /// Triangles of the given groups; with `prepass`, only those whose box overlaps a partner object's box.
    void collectTriangles(const std::vector<Group>& groups, bool prepass) {
        constexpr std::size_t kGroupsPerTask = 256;
        const std::size_t tasks = (groups.size() + kGroupsPerTask - 1) / kGroupsPerTask;
        if (m_taskTris.size() < tasks) m_taskTris.resize(tasks);
        m_pool.parallelFor(tasks, 1, [&](std::size_t begin, std::size_t end) {
            thread_local std::vector<Tri> kept;  // per thread: neighbouring tasks' vectors share cache lines
            for (std::size_t task = begin; task < end; ++task) {
                kept.clear();
                const std::size_t last = std::min(groups.size(), (task + 1) * kGroupsPerTask);
                for (std::size_t i = task * kGroupsPerTask; i < last; ++i) {
                    const Group& g = groups[i];
                    const std::vector<Aabb>& boxes = *m_boxesOf[g.object];
                    const bool test = prepass && m_partners[g.object].size() <= 16;
                    for (std::uint32_t k = g.first; k < g.first + g.count; ++k) {
                        const std::uint32_t t = m_order[g.object][k];
                        if (test && !overlapsPartner(g.object, boxes[t])) continue;
                        kept.push_back({g.object, t});
                    }
                }
                m_taskTris[task].assign(kept.begin(), kept.end());
            }
        });
        m_tris.clear();
        for (std::size_t task = 0; task < tasks; ++task)
            m_tris.insert(m_tris.end(), m_taskTris[task].begin(), m_taskTris[task].end());
    }

    /// Without GPU levels, in one pass on every worker: each active mesh's triangle boxes (those not kept from an
    /// earlier frame), and its surviving triangles — those whose box overlaps a partner's box (with more than 16
    /// partners, every triangle of a run of k whose joint box does, as the group filter would).
    void collectDirect() {
        const auto k = static_cast<std::uint32_t>(m_settings.groupSize);
        const std::uint32_t range = k * std::max<std::uint32_t>(1, 8192 / k);
        m_ranges.clear();
        for (std::uint32_t o = 0; o < m_valid.size(); ++o) {
            if (!m_active[o] || !isMesh(o)) continue;
            const auto n = static_cast<std::uint32_t>(meshOf(o).triangles.size());
            for (std::uint32_t first = 0; first < n; first += range)
                m_ranges.push_back({o, first, std::min(n, first + range)});
        }
        if (m_rangeKept.size() < m_ranges.size()) m_rangeKept.resize(m_ranges.size());
        // The union of each object's partners' boxes: one test rejects the triangles far from all of them.
        m_partnerUnion.assign(m_valid.size(), Aabb{});
        for (std::uint32_t o = 0; o < m_valid.size(); ++o)
            for (std::uint32_t p : m_partners[o]) m_partnerUnion[o].grow(m_valid[p].box);
        const double inflate = 0.5 * m_settings.margin;
        m_pool.parallelFor(m_ranges.size(), 1, [&](std::size_t begin, std::size_t end) {
            thread_local std::vector<std::uint32_t> kept;  // per thread: neighbouring ranges' vectors share lines
            for (std::size_t r = begin; r < end; ++r) {
                const Range& rg = m_ranges[r];
                const TriangleMesh& mesh = meshOf(rg.object);
                std::vector<Aabb>& boxes = *m_boxesOf[rg.object];
                const bool compute = m_staticEntry[rg.object] == nullptr;
                kept.clear();
                const Aabb& near = m_partnerUnion[rg.object];
                if (m_partners[rg.object].size() <= 16) {
                    for (std::uint32_t t = rg.begin; t < rg.end; ++t) {
                        // Only kept triangles' boxes are read later: the others are not stored (memory traffic).
                        const Aabb box = compute ? triangleBounds(mesh, t, inflate) : boxes[t];
                        if (!box.overlaps(near) || !overlapsPartner(rg.object, box)) continue;
                        if (compute) boxes[t] = box;
                        kept.push_back(t);
                    }
                } else {
                    for (std::uint32_t first = rg.begin; first < rg.end; first += k) {
                        const std::uint32_t last = std::min(rg.end, first + k);
                        Aabb box;
                        for (std::uint32_t t = first; t < last; ++t) {
                            if (compute) boxes[t] = triangleBounds(mesh, t, inflate);
                            box.grow(boxes[t]);
                        }
                        if (!box.overlaps(near) || !overlapsPartner(rg.object, box)) continue;
                        for (std::uint32_t t = first; t < last; ++t) kept.push_back(t);
                    }
                }
                m_rangeKept[r].assign(kept.begin(), kept.end());
            }
        });
        for (std::size_t r = 0; r < m_ranges.size(); ++r) {  // ranges in object and triangle order: sorted lists
            auto& list = m_survivingTriangles[m_ranges[r].object];
            list.insert(list.end(), m_rangeKept[r].begin(), m_rangeKept[r].end());
        }
    }

    void runTriangleLevel(const std::vector<std::uint32_t>& proxies, Stats& stats) {
        beginLevel(stats);
        for (const Tri& t : m_tris) addTriangleItem(t.object, &t.triangle, 1, (*m_boxesOf[t.object])[t.triangle]);
        for (std::uint32_t o : proxies) addBoxItem(o, m_objectBox[o], m_valid[o].box);
        pruneLevel("triangles", stats);
        finishFromTriangles(m_survivors);
    }

    /// Surviving triangles per object (`alive` empty: all of m_tris). Proxies only ever act as occluders.
    void finishFromTriangles(const std::vector<std::uint8_t>& alive) {
        for (std::size_t i = 0; i < m_tris.size(); ++i)
            if (alive.empty() || alive[i]) m_survivingTriangles[m_tris[i].object].push_back(m_tris[i].triangle);
        for (auto& list : m_survivingTriangles)
            if (!std::is_sorted(list.begin(), list.end())) std::sort(list.begin(), list.end());
    }

    std::vector<std::uint32_t> activeProxies() const {
        std::vector<std::uint32_t> proxies;
        for (std::uint32_t o = 0; o < m_valid.size(); ++o)
            if (m_active[o] && !isMesh(o)) proxies.push_back(o);
        return proxies;
    }

    /// After a groups level whose items were `groups` followed by `proxies`: keeps the survivors of both.
    void keepSurvivingGroups(std::vector<Group>& groups, std::vector<std::uint32_t>& proxies) const {
        std::vector<Group> kept;
        for (std::size_t g = 0; g < groups.size(); ++g)
            if (m_survivors[g]) kept.push_back(groups[g]);
        std::vector<std::uint32_t> keptProxies;
        for (std::size_t p = 0; p < proxies.size(); ++p)
            if (m_survivors[groups.size() + p]) keptProxies.push_back(proxies[p]);
        groups.swap(kept);
        proxies.swap(keptProxies);
    }

    static std::size_t triangleCount(const std::vector<Group>& groups) {
        std::size_t n = 0;
        for (const Group& g : groups) n += g.count;
        return n;
    }

    /// The levels, cluster by cluster (clustersOf): each cluster's geometry goes to the device relative to its own
    /// centre and each level's views are fitted to that cluster, so objects far from each other cost what near ones
    /// cost and their coordinates keep the float precision the error bounds assume. m_active and m_groups hold one
    /// cluster while its levels run and are restored afterwards (also when a level throws).
    void runLevels(bool paper, Stats& stats) {
        if (!m_gpuLevels) {
            collectDirect();
            return;
        }
        const std::vector<std::vector<std::uint32_t>> clusters = clustersOf(m_active, m_pairs, m_valid);
        stats.clusters += clusters.size();
        struct Restore {
            GpuCuller& self;
            std::vector<std::uint8_t> active;
            std::vector<Group> groups;
            ~Restore() {
                self.m_active.swap(active);
                self.m_groups.swap(groups);
            }
        } restore{*this, m_active, m_groups};
        for (const std::vector<std::uint32_t>& cluster : clusters) {
            m_active.assign(m_valid.size(), 0);
            for (std::uint32_t o : cluster) m_active[o] = 1;
            m_groups.clear();
            for (const Group& g : restore.groups)
                if (m_active[g.object]) m_groups.push_back(g);
            m_uploaded = false;
            if (!rasterisable(cluster)) {
                // Relative coordinates beyond what float positions and depths carry: no pruning, every triangle
                // that the box pre-pass keeps goes to the exact stage (sound, and rare: extents above 1e30).
                ++stats.unrasterisedClusters;
                collectTriangles(m_groups, true);
                finishFromTriangles({});
            } else if (paper) {
                runPaperPipeline(stats);
            } else {
                runAutoPipeline(stats);
            }
        }
    }

    /// Largest cluster extent whose coordinates, relative to its centre, the GPU levels take as floats (with room
    /// for the views' arithmetic below FLT_MAX).
    static constexpr double kRasterisableExtent = 1e30;

    bool rasterisable(const std::vector<std::uint32_t>& cluster) const {
        Aabb box;
        for (std::uint32_t o : cluster) box.grow(m_valid[o].box);
        return box.isEmpty() || box.extent().maxCoeff() <= kRasterisableExtent;
    }

    /// CPU pre-pass (done in buildGroups), group boxes on the GPU, triangles of the surviving groups on the GPU;
    /// a level whose input is small enough goes straight to the exact stage, and GPU levels are skipped where they
    /// do not pay (Settings::gpuLevels).
    void runAutoPipeline(Stats& stats) {
        std::vector<std::uint32_t> proxies = activeProxies();
        std::vector<Group> groups = m_groups;
        if (m_gpuLevels && triangleCount(groups) > m_settings.exactThreshold) {
            beginLevel(stats);
            for (std::size_t g = 0; g < groups.size(); ++g)
                addBoxItem(groups[g].object, m_groupBox[g], groups[g].box);
            for (std::uint32_t o : proxies) addBoxItem(o, m_objectBox[o], m_valid[o].box);
            pruneLevel("groups", stats);
            keepSurvivingGroups(groups, proxies);
        }
        collectTriangles(groups, true);
        if (m_gpuLevels && m_tris.size() > m_settings.exactThreshold)
            runTriangleLevel(proxies, stats);
        else
            finishFromTriangles({});
    }

    /// The paper's pipeline: objects as boxes, objects as triangles, groups as triangles, triangles.
    void runPaperPipeline(Stats& stats) {
        std::vector<std::uint32_t> objects;
        for (std::uint32_t o = 0; o < m_valid.size(); ++o)
            if (m_active[o]) objects.push_back(o);
        std::vector<std::uint32_t> proxies = activeProxies();

        auto keepSurvivors = [&](std::vector<std::uint32_t>& list) {
            std::vector<std::uint32_t> kept;
            for (std::size_t i = 0; i < list.size(); ++i)
                if (m_survivors[i]) kept.push_back(list[i]);
            list.swap(kept);
        };
        beginLevel(stats);
        for (std::uint32_t o : objects) addBoxItem(o, m_objectBox[o], m_valid[o].box);
        pruneLevel("objects-box", stats);
        keepSurvivors(objects);

        beginLevel(stats);
        for (std::uint32_t o : objects) {
            if (isMesh(o))
                addTriangleItem(o, m_order[o].data(), static_cast<std::uint32_t>(m_order[o].size()), m_valid[o].box);
            else
                addBoxItem(o, m_objectBox[o], m_valid[o].box);
        }
        pruneLevel("objects", stats);
        keepSurvivors(objects);
        std::vector<std::uint8_t> objectAlive(m_valid.size(), 0);
        for (std::uint32_t o : objects) objectAlive[o] = 1;

        std::vector<Group> groups;
        for (const Group& g : m_groups)
            if (objectAlive[g.object]) groups.push_back(g);
        std::vector<std::uint32_t> levelProxies;
        for (std::uint32_t o : proxies)
            if (objectAlive[o]) levelProxies.push_back(o);
        beginLevel(stats);
        for (const Group& g : groups) addTriangleItem(g.object, &m_order[g.object][g.first], g.count, g.box);
        for (std::uint32_t o : levelProxies) addBoxItem(o, m_objectBox[o], m_valid[o].box);
        pruneLevel("groups", stats);
        keepSurvivingGroups(groups, levelProxies);
        collectTriangles(groups, false);
        runTriangleLevel(levelProxies, stats);
    }

    /// Pairs are a function of the input alone: mesh pairs with at least one triangle pair within the margin
    /// (exact), pairs with a box proxy by a CPU box test. The GPU levels only decide how much exact work is left.
    void assemblePairs(Result& result) {
        std::vector<ExactJob> jobs;
        std::vector<std::size_t> jobPair;
        std::vector<BoxJob> boxJobs;
        std::vector<std::size_t> boxJobPair;
        for (const auto& [a, b] : m_pairs) {
            ObjectPair pair;
            pair.a = a;
            pair.b = b;
            if (isMesh(a) && isMesh(b)) {
                if (m_survivingTriangles[a].empty() || m_survivingTriangles[b].empty()) continue;
                pair.hasTriangles = true;
                jobs.push_back({a, b, &m_survivingTriangles[a], &m_survivingTriangles[b], m_boxesOf[a], m_boxesOf[b]});
                jobPair.push_back(result.pairs.size());
            } else if (isMesh(a) || isMesh(b)) {
                const std::uint32_t mesh = isMesh(a) ? a : b;
                const Aabb& box = m_valid[isMesh(a) ? b : a].box;
                if (!m_gpuLevels) {
                    // The mesh's surviving triangles include every one whose box overlaps this partner's: its tree
                    // answers in O(log n) (a landscape under hundreds of bodies).
                    boxJobs.push_back({&m_survivingTriangles[mesh], m_boxesOf[mesh], box});
                    boxJobPair.push_back(result.pairs.size());
                } else if (!meshTouchesBox(meshOf(mesh), box, m_settings.margin)) {  // GPU levels prune survivors
                    continue;
                }
            }
            result.pairs.push_back(std::move(pair));
        }
        m_exact.run(*m_objects, jobs, m_settings.margin, m_settings.exactTriangles, m_jobResults, result.stats, boxJobs,
                    &m_touches);
        std::vector<std::uint8_t> keep(result.pairs.size(), 1);
        for (std::size_t j = 0; j < boxJobs.size(); ++j) keep[boxJobPair[j]] = m_touches[j];
        for (std::size_t j = 0; j < jobs.size(); ++j) {
            result.pairs[jobPair[j]].triangles = std::move(m_jobResults[j].triangles);
            keep[jobPair[j]] = !result.pairs[jobPair[j]].triangles.empty();
        }
        std::size_t out = 0;
        for (std::size_t i = 0; i < result.pairs.size(); ++i) {
            if (!keep[i]) continue;
            if (out != i) result.pairs[out] = std::move(result.pairs[i]);
            ++out;
        }
        result.pairs.resize(out);
        std::vector<std::uint8_t> inPcs(m_valid.size(), 0);
        for (const ObjectPair& p : result.pairs) inPcs[p.a] = inPcs[p.b] = 1;
        for (std::uint32_t o = 0; o < inPcs.size(); ++o)
            if (inPcs[o]) result.pcs.push_back(o);
    }

    static constexpr std::uint32_t kNoOwner = 0xFFFFFFFFu;

    Settings m_settings;
    TaskPool m_pool;  ///< before m_exact, which runs on it
    ExactStage m_exact;
    std::unique_ptr<PruningBackend> m_backend;  ///< null: no GPU levels (see openBackend)
    std::string m_gpuUnavailable;               ///< why there is no backend (Stats::gpuUnavailable)

    // Per-frame state (members to reuse allocations).
    const std::vector<Object>* m_objects = nullptr;
    std::vector<ValidatedObject> m_valid;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> m_pairs;
    std::vector<std::vector<std::uint32_t>> m_partners;
    std::vector<std::uint8_t> m_active;
    WorldMeshes m_world;  ///< world-space meshes of this frame's kept objects that come with a transform
    std::vector<Group> m_groups;
    struct Range {
        std::uint32_t object;
        std::uint32_t begin;
        std::uint32_t end;
    };
    std::vector<Range> m_ranges;             ///< triangle ranges of the active meshes, for the workers
    std::vector<Group> m_groupCandidates;    ///< every group of the active meshes, before the pre-pass
    std::vector<std::uint8_t> m_groupKept;
    std::vector<std::vector<std::uint32_t>> m_order;  ///< per active mesh: triangles in Morton order
    std::vector<std::vector<Aabb>> m_triangleBoxes;   ///< per active non-static mesh: every triangle's box
    std::vector<std::vector<Aabb>*> m_boxesOf;  ///< per active mesh: triangle boxes (inflated by margin / 2), of
                                                ///< every triangle (static meshes; any with GPU levels) or only of
                                                ///< its surviving ones (others, CPU path)
    std::vector<std::uint8_t> m_needBoxes;            ///< per object: its boxes are computed this frame
    std::unordered_map<std::uint64_t, StaticEntry> m_static;  ///< by Object::staticKey
    std::vector<StaticEntry*> m_staticEntry;          ///< per object: its entry (null: not static or not cached)
    std::vector<std::uint8_t> m_known;                ///< per object: validation kept from an earlier frame
    std::uint64_t m_frame = 0;
    std::vector<std::uint32_t> m_groupBox;
    std::vector<std::uint32_t> m_objectBox;
    std::vector<std::uint32_t> m_baseTriangle;
    std::vector<MeshSlot> m_appended;  ///< uploadGeometry: the meshes written this frame
    Vec3 m_origin = Vec3::Zero();
    std::uint64_t m_regionEpoch = 0;  ///< bumped whenever the resident static region is rebuilt (0: none yet)
    double m_regionExtent = 0.0;      ///< extent of the active objects when the region's origin was chosen
    std::size_t m_regionVertices = 0;
    std::size_t m_regionTriangles = 0;
    bool m_uploaded = false;
    AutoLevels m_auto;             ///< GpuLevels::Auto: the timing trial and its decision
    AutoLevels::Path m_autoPath = AutoLevels::Path::Cpu;  ///< the path AutoLevels chose for this frame
    bool m_autoActive = false;     ///< this frame's path was AutoLevels' choice
    bool m_gpuLevels = false;  ///< whether GPU levels run this frame (Settings::gpuLevels, the device, the pipeline)
    GpuGeometry m_geometry;
    LevelItems m_items;
    std::vector<std::uint8_t> m_survivors;
    std::vector<std::uint32_t> m_ownerId;
    std::uint32_t m_ownerCount = 0;
    std::vector<Tri> m_tris;
    std::vector<std::vector<Tri>> m_taskTris;
    std::vector<std::vector<std::uint32_t>> m_rangeKept;  ///< collectDirect: survivors per triangle range
    std::vector<Aabb> m_partnerUnion;                     ///< collectDirect: union of each object's partners' boxes
    std::vector<std::vector<std::uint32_t>> m_survivingTriangles;
    std::vector<ExactJobResult> m_jobResults;
    std::vector<std::uint8_t> m_touches;
};

}  // namespace

std::unique_ptr<Culler> createGpuCuller(const Settings& settings, const PruningBackendFactory& makeBackend) {
    const std::string error = settings.validate();
    if (!error.empty()) throw std::invalid_argument("cullide::Settings: " + error);
    return std::make_unique<GpuCuller>(settings, makeBackend);
}

std::unique_ptr<Culler> createGpuCuller(const Settings& settings) {
    return createGpuCuller(settings, createGlPruningBackend);
}

}  // namespace cullide
