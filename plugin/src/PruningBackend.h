// The seam between the frame pipeline (GpuCuller, LevelPipelines) and what runs CULLIDE's image-space visibility
// test: the GL implementation (gl/VisibilityPass) and the CPU reference (ReferenceVisibility), which computes the
// same pixels in the same float arithmetic and is the oracle of the GL one. A backend runs a whole level: its
// iterations, each view fitted to what the last one left and the stop rule (VisibilityLevel.h) — the GL one on the
// device, without waiting between iterations.
#pragma once

#include "Deadline.h"
#include "bindings.h"
#include "cullide/Stats.h"
#include "cullide/Types.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide {

/// A mesh given in its own frame (Object::transform) whose world positions the backend maps itself: its vertices
/// local[3 * localBase ..] (count of them) go to vertices baseVertex .. of the cluster as devicePosition(
/// transformPoint(transform, v), origin) would write them, bit for bit.
struct MappedMesh {
    Transform transform;
    std::uint32_t localBase = 0;
    std::uint32_t baseVertex = 0;
    std::uint32_t count = 0;
};

/// Geometry of the frame's active cluster, uploaded once per cluster: positions and boxes relative to the upload
/// origin, in float (what the visibility test rasterises).
struct GpuGeometry {
    /// xyz per vertex, of every vertex before the mapped meshes' (which follow: vertexCount() in all).
    std::vector<float> positions;
    std::vector<std::uint32_t> indices;  ///< 3 global vertex indices per triangle
    /// Per triangle: each mesh's triangles in its spatial order (FrameState::order), as global triangle indices —
    /// ordered[b + k] = b + order[k] for a mesh whose triangles start at b — so that a group's triangles are a range
    /// of it (ObjectRange).
    std::vector<std::uint32_t> ordered;
    /// The first keptPositions floats of `positions`, keptIndices of `indices`, keptOrdered of `ordered` and
    /// keptLocal of `local` are the same as in the previous upload (static geometry, and meshes that did not change: a
    /// deforming mesh's indices, a mesh at rest, a rigid mesh's own vertices, an order kept between frames): what the
    /// device already holds of them is not sent again.
    std::size_t keptPositions = 0;
    std::size_t keptIndices = 0;
    std::size_t keptOrdered = 0;
    /// The vertices of the mapped meshes in their own frames (xyz per vertex) and the meshes: a rigid mesh's
    /// vertices stay on the device, its transform is all that is sent while it moves.
    std::vector<double> local;
    std::size_t keptLocal = 0;
    std::vector<MappedMesh> mapped;
    Vec3 origin = Vec3::Zero();         ///< of the upload, in world space
    std::vector<float> boxes;           ///< min xyz, max xyz per box (rounded outwards)
    /// Boxes the device builds after these (group_boxes.comp), from the positions above and the mapped meshes':
    /// built box i (box boxes.size() / 6 + i) is the box of the vertices of the triangles ordered[builtRanges[2i] ..
    /// builtRanges[2i] + builtRanges[2i + 1]) (one group of a mesh that moves or deforms; at least one triangle),
    /// grown by builtInflate on each side in float — the box of what the triangle level rasterises, which the views'
    /// error bounds hold to the true triangles as they do the positions (allBoxes computes the same on the CPU).
    std::vector<std::uint32_t> builtRanges;
    float builtInflate = 0.0f;
    double coordinateBound = 0.0;       ///< max |coordinate| over positions and boxes (for error bounds)

    std::size_t vertexCount() const {
        std::size_t n = positions.size() / 3;
        for (const MappedMesh& m : mapped) n = std::max<std::size_t>(n, std::size_t{m.baseVertex} + m.count);
        return n;
    }
};

/// A world position as the device holds it: relative to the upload origin, rounded to float (0 where the position
/// is not finite: a vertex no triangle uses may be NaN).
inline void devicePosition(const Vec3& world, const Vec3& origin, float out[3]) {
    const Vec3 r = world.allFinite() ? Vec3(world - origin) : Vec3::Zero();
    for (int a = 0; a < 3; ++a) out[a] = static_cast<float>(r[a]);
}

/// Every vertex of `geometry` as the device holds it: `positions`, then the mapped meshes' vertices mapped on the CPU
/// (the reference backend's copy of what the GL one maps on the device). Between the mapped meshes lie the places of
/// meshes mapped by other uploads (MeshSlots), which the device still holds and which are 0 here: only `positions`
/// and the mapped meshes' own vertices are this upload's.
std::vector<float> allPositions(const GpuGeometry& geometry);

/// Every box of `geometry` as the device holds it: `boxes`, then the built ones (GpuGeometry::builtRanges) from
/// `positions` (allPositions), as group_boxes.comp builds them, bit for bit.
std::vector<float> allBoxes(const GpuGeometry& geometry, const std::vector<float>& positions);

/// A run of items of one object in a level described by its objects (LevelItems::objectRanges): item
/// itemBegin + j (j < count) is box first + j (kind CULLIDE_RANGE_BOXES: a group's box, or a proxy's own), or the
/// triangle ordered[first + j] of the upload (CULLIDE_RANGE_TRIANGLES: the object's triangles in its spatial order),
/// owned by `owner`. In a level that inherits, its parent is item parent + j (boxes) or parent + j / groupSize
/// (triangles: the j-th triangle is in the object's group j / groupSize) of the level before. The box pre-pass keeps
/// it where its box meets one of its partners' boxes (partnerBoxes[partnerBegin .. partnerEnd), boxes of the upload)
/// grown by the level's prepassSlack, or always (kind | CULLIDE_RANGE_KEEP). Laid out as start.comp reads it.
struct ObjectRange {
    std::uint32_t itemBegin = 0;
    std::uint32_t count = 0;
    std::uint32_t first = 0;
    std::uint32_t parent = 0;
    std::uint32_t partnerBegin = 0;
    std::uint32_t partnerEnd = 0;
    std::uint32_t owner = 0;
    std::uint32_t kind = 0;
};
static_assert(sizeof(ObjectRange) == 4 * CULLIDE_RANGE_WORDS, "start.comp's range records");

/// The device exact stage after a level described by its objects (a deferred triangle level): per range r, the ranges
/// of the meshes its triangles may meet are partners[partnerBegin[r] .. partnerBegin[r + 1]) (each object pair listed
/// under one of its two ranges). The backend writes every pair of surviving triangles, one from r and one from a
/// partner, whose boxes (of the positions) meet within `slack`, unless DeviceExactFilter.h's filter (with `reach`; off
/// without `filter`) certifies it apart; each pair with that filter's verdict (DeferredLevel::exactPairs).
struct ExactRequest {
    bool run = false;
    bool filter = true;  ///< false: every candidate is written undecided (Settings::exactTriangles off)
    float slack = 0.0f;  ///< exactSlack (DeviceExact.h)
    float reach = 0.0f;  ///< exactReach (DeviceExact.h)
    /// Partner items per chunk (whole groups: llvmpipe's 65,535 loop iterations per invocation hold a chunk's group
    /// pairs, groupSize^2 triangle pairs each), and the chunks of the longest partner list.
    std::uint32_t chunkItems = 0;
    std::uint32_t chunks = 0;
    std::vector<std::uint32_t> partnerBegin;  ///< ranges + 1
    std::vector<std::uint32_t> partners;      ///< range indices
    /// Per range: the box of its first item's group (a triangle range's item j is in group j / groupSize, whose box is
    /// this one + j / groupSize; 0 for a range of boxes). A group whose box misses a triangle's holds no pair with it.
    std::vector<std::uint32_t> groupBoxes;
    void clear() {
        run = false;
        filter = true;
        slack = reach = 0.0f;
        chunkItems = chunks = 0;
        partnerBegin.clear();
        partners.clear();
        groupBoxes.clear();
    }
};

/// The items of one level. Item i belongs to owner[i] (a compact object id) and is drawn as the primitives
/// prims[primBegin[i] .. primBegin[i + 1]) (a triangle index, or a box index | CULLIDE_PRIM_BOX_BIT) — or, in a level
/// described by its objects (describedByObjects()), as the one primitive its range gives it on the device.
struct LevelItems {
    std::vector<std::uint32_t> owner;
    std::vector<std::uint32_t> primBegin{0};
    std::vector<std::uint32_t> prims;
    std::vector<Aabb> bounds;  ///< per item, relative to the upload origin, inflated by nothing
    /// Non-empty: a level described by its objects, in ranges of items ordered by itemBegin and covering every item.
    /// The backend generates each item's primitive, owner and start — its parent's survival where `inheritsParents`
    /// (the level the backend ran just before, pruneLevelAhead: its survivors never leave the device), and the box
    /// pre-pass — and fits the first view to the items that start alive on the device, as an iteration's end fits the
    /// next one: nothing per item and no view is sent (LevelStart::view is not used). `owner`, `prims` and `bounds`
    /// are left empty: nothing is built per item on the CPU either.
    std::vector<ObjectRange> objectRanges;
    std::vector<std::uint32_t> partnerBoxes;
    std::size_t objectItems = 0;  ///< the ranges' items, summed (the level's size)
    bool inheritsParents = false;
    std::uint32_t groupSize = 1;  ///< triangles per parent (CULLIDE_RANGE_TRIANGLES ranges that inherit)
    /// How far the pre-pass grows a partner's box (float, rounded up): the float error of the boxes and positions
    /// as the device holds them, and for triangles the margin / 2 their boxes are not grown by.
    float prepassSlack = 0.0f;
    ExactRequest exact;  ///< a deferred level described by its objects: the device exact stage after it
    bool describedByObjects() const { return !objectRanges.empty(); }
    std::size_t primitiveCount() const { return describedByObjects() ? size() : prims.size(); }
    std::size_t size() const { return describedByObjects() ? objectItems : owner.size(); }
    /// Whether item i is exactly primitive i (one primitive each): primBegin need not be sent.
    bool onePrimitiveEach() const {
        for (std::size_t i = 0; i < primBegin.size(); ++i)
            if (primBegin[i] != i) return false;
        return true;
    }
    void clear() {
        owner.clear();
        primBegin.assign(1, 0);
        prims.clear();
        bounds.clear();
        objectRanges.clear();
        partnerBoxes.clear();
        objectItems = 0;
        inheritsParents = false;
        groupSize = 1;
        prepassSlack = 0.0f;
        exact.clear();
    }
};

/// The orthographic view box of one iteration and the float parameters every view of it uses (the shaders'
/// uniforms), per world axis. Made by fitView (VisibilityLevel.h).
struct View {
    Aabb box;  ///< relative to the upload origin
    float lo[3];          ///< box minimum
    float pixelScale[3];  ///< pixels per unit
    float depthScale[3];  ///< normalized depth per unit
    float halfSize[3];    ///< reliable mode: half side of the tested pixel square (half pixel + margin + slack)
    float depthPad[3];    ///< reliable mode: margin + slack added to depth ranges (normalized depth)
};

/// What one iteration leaves: the items still alive and what the next view is fitted to.
struct IterationResult {
    /// Compute back-end invocations whose footprint exceeded the loop bound: the iteration pruned nothing.
    std::uint32_t overflows = 0;
    std::uint32_t alive = 0;
    std::uint32_t ownerMin = 0;  ///< smallest and largest owner among the alive items (unset when none)
    std::uint32_t ownerMax = 0;
    Aabb bounds;  ///< of the alive items' boxes as uploaded (deviceBoundsOf, VisibilityLevel.h)
};

/// One iteration of a level as it ran: its view, its owner-id bits and what it left (a level's trace, for tests).
struct IterationTrace {
    View view;
    std::uint32_t idBits = 0;
    IterationResult result;
};

/// How a level starts: the first iteration's view and owner-id bits (fitted on the CPU to the items' bounds), and
/// the coordinate bound every next view is fitted with (fitView).
struct LevelStart {
    View view;
    std::uint32_t idBits = 1;
    double coordinateBound = 0.0;
    /// The level's place in the frame (0 for its first level): a level in the same place of the next frame most
    /// often runs as many iterations (the GL back-end issues that many before it waits).
    std::size_t place = 0;
};

/// Thrown by pruneLevel where the level run ahead before it (pruneLevelAhead) stopped early on the device (its records
/// needed building again, or it needed more iterations than were issued): both levels run again, the first one
/// waited for (Stats::levelReruns). Nothing of the frame is lost.
struct LevelsRerun {};

/// A level run with its read-back deferred (PruningBackend::pruneLevelDeferred), as collect() finds it.
struct DeferredLevel {
    /// The level ran as one chain, and so did the level run ahead before it: `survivors` is its alive set, as
    /// pruneLevel gives it. Otherwise one of them stopped early on the device (records to build again, more
    /// iterations needed than were issued): nothing of the level is known, and it runs again, waited for.
    bool complete = false;
    std::vector<std::uint8_t> survivors;
    /// The device exact stage ran (LevelItems::exact) and every pair it found fit its buffer: exactPairs holds them,
    /// two words each (the items, the second | CULLIDE_EXACT_WITHIN where the filter certified the pair).
    bool exactRan = false;
    std::vector<std::uint32_t> exactPairs;
};

/// A backend failure in the middle of a frame (a GL error). The culler finishes that frame without pruning: every
/// triangle the CPU pre-pass keeps goes to the exact stage, so no contact is lost.
class BackendError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class PruningBackend {
public:
    virtual ~PruningBackend() = default;
    PruningBackend() = default;
    PruningBackend(const PruningBackend&) = delete;
    PruningBackend& operator=(const PruningBackend&) = delete;

    /// A frame starts: what a frame abandoned half way left behind (levels deferred or run ahead and never read back)
    /// is dropped.
    virtual void beginFrame() = 0;
    /// Takes the cluster's geometry; `geometry` must stay alive (unchanged) until the next upload.
    virtual void upload(const GpuGeometry& geometry, Stats& stats) = 0;
    /// Forgets what was uploaded (after a GL error): the next upload sends everything.
    virtual void forgetUploads() = 0;
    /// Bytes held on the device (0 for a CPU backend).
    virtual std::size_t deviceBytes() const = 0;
    /// GL_RENDERER and the device chosen (Stats::renderer, Stats::device).
    virtual std::string renderer() const = 0;
    virtual std::string device() const = 0;
    /// Whether it runs on a hardware GPU (not a software renderer, not the CPU reference).
    virtual bool hardwareDevice() const { return false; }

    /// Runs one level over `items` (at least two owners, owner ids below 2^16): every item alive, then at most
    /// Settings::maxIterations iterations, the first with start.view, each next one with the view fitted to the
    /// items the last one left (fitView, idBitsFor of their largest owner), until stepAfter (VisibilityLevel.h) says
    /// stop. survivors[i]: 1 when item i is alive at the end (all 0 when one owner is left). Adds the iterations
    /// and the items after each (LevelStats::itemsPerIteration, noteIteration) to `level`. `trace`, when given,
    /// receives every iteration run, in order (tests: the GL back-end reads it back off the books).
    virtual void pruneLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                            LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) = 0;
    /// Runs a level as pruneLevel does, whose survivors stay with the backend for the next level's items to inherit
    /// (LevelItems::inheritsParents). The GL back-end issues it and returns at once, unless the level in its place stopped
    /// early last time (then it waits, as pruneLevel): its stats (stats.levels[levelIndex]) and trace are complete
    /// once the next level has been waited for (pruneLevel, which may throw LevelsRerun) or settle().
    virtual void pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex,
                                 Stats& stats, std::vector<IterationTrace>* trace) = 0;
    /// Waits for a level run ahead that no level followed, and completes its stats.
    virtual void settle(Stats& stats) = 0;
    /// Runs a level as pruneLevel does (it may inherit the level run ahead before it), whose result is read back
    /// with every other level deferred since the last collect(): the GL back-end issues it and returns at once, so a
    /// frame of several clusters waits once. Its stats (stats.levels[levelIndex], and the level run ahead's) and trace
    /// are complete after collect(); `trace` must stay alive until then. Where the level in its place stopped early
    /// last time it is waited for at once (as pruneLevel), and collect() hands its survivors over.
    virtual void pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex,
                                    Stats& stats, std::vector<IterationTrace>* trace) = 0;
    /// Waits, at most until `until`, for the levels deferred since the last collect(): one blocking read-back for all
    /// of them. Returns false where `until` came first (the deferred levels are dropped, nothing is collected);
    /// otherwise results[k] is what the k-th deferred level left. The read-back is the last deferred level's that was
    /// not waited for at once: its stats count it (blockingReadBacks, waitMs, and the wait in cpuMs).
    virtual bool collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) = 0;
};

}  // namespace cullide
