// Per-stage statistics of one culling frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cullide {

/// One GPU pruning level (objects, groups or triangles).
struct LevelStats {
    std::string name;                       ///< "objects-box", "objects", "groups", "triangles"
    /// Items entering each iteration (the first: those alive at the level's start — all of them, or, in a level that
    /// inherits the last one's survivors and ran, those whose parent survived and that the box pre-pass keeps; a level
    /// that ends on the CPU before it runs, with fewer than two owners, lists all its items); last entry = survivors.
    std::vector<std::size_t> itemsPerIteration;
    std::size_t iterations = 0;             ///< visibility iterations run (the last may have changed nothing)
    std::size_t primitivesDrawn = 0;        ///< records the visibility passes ran over (all passes, all views)
    std::size_t draws = 0;
    double cpuMs = 0.0;                     ///< wall time spent on the CPU side of the level (incl. waiting)
    /// Of cpuMs, GL back-end: sending the level's items and issuing the build of their boxes and records on the
    /// device (at its start, and again where the view shrank enough to refit the bands); nothing in it waits for the
    /// device: setupMs + waitMs <= cpuMs.
    double setupMs = 0.0;
    /// Of setupMs, the GL calls that send the items (primitives, owners) and clear their device state.
    double setupSendMs = 0.0;
    /// GL back-end: records built for the level's iterations (one per primitive; on the compute back-end one per band
    /// of a primitive's footprint), over all builds, and the builds: one at the start, one per refit of the bands.
    std::size_t records = 0;
    std::size_t recordBuilds = 0;
    /// Of recordBuilds, those that needed more records than the device's record buffers held: they wrote none, their
    /// iteration pruned nothing, and they were built again after the buffers grew (kept between frames).
    std::size_t shortBuilds = 0;
    /// GL back-end: iterations issued after the device had stopped the level's chain (it stops by itself when the
    /// set stops changing): their passes were dispatched with empty arguments and ran nothing. A level issues as
    /// many iterations as the level in its place ran last time; more when that was not enough (blockingReadBacks).
    std::size_t idleIterations = 0;
    /// Of cpuMs, GL back-end: blocked in read-backs, i.e. waiting for the device to finish the work submitted
    /// before. The rest of cpuMs is issuing commands and the level loop.
    double waitMs = 0.0;
    /// GL back-end: read-backs that blocked on the device: one per level waited for (its counters, the chain of
    /// iterations and the alive set), and one more for each time the chain stopped to have its records built again (a
    /// short build, LevelStats::shortBuilds; a view that shrank to a quarter) or ran past the iterations issued. A
    /// level run ahead has none (its chain comes with the next level's read-back); the deferred levels of a frame
    /// share one, which the last of them counts (with its wait in waitMs and cpuMs).
    std::size_t blockingReadBacks = 0;
    /// GL back-end: the level was issued and read back with the frame's other deferred levels (the Auto pipeline's
    /// triangle level of each cluster): one read-back per frame however many clusters it has.
    bool deferred = false;
    /// GPU time of the level's iterations and record builds from timer queries (one span from the level's first pass
    /// to its read-back, or to the end of its issue where it runs ahead or is deferred: read after the read-back that
    /// brings its chain), and of its exact stage (exactGpuMs). Only meaningful with gpuTimingValid; 0 otherwise.
    double gpuMs = 0.0;
    /// Of gpuMs, the device exact stage that followed the level (Settings::deviceExact; a deferred triangle level),
    /// timed by a span of its own. 0 where it did not run or gpuTimingValid is false.
    double exactGpuMs = 0.0;
    /// true when every iteration of the level was timed by an available, plausible timer-query result (at most
    /// the CPU wall time of the same span): false without timer queries and where a driver reports nonsense
    /// (llvmpipe's first timer result in a context is an absolute time: the machine's uptime).
    bool gpuTimingValid = true;
};

struct Stats {
    std::string renderer;   ///< GL_RENDERER of the context used ("cpu-reference" for the reference culler,
                            ///< "cpu-visibility-reference" for createVisibilityReferenceCuller; empty when the culler
                            ///< holds no GL context)
    std::string device;     ///< which GL device / platform was chosen ("none" when no GL context was opened, "cpu"
                            ///< for createVisibilityReferenceCuller)
    /// Empty when the culler holds a GL context; otherwise why not: no usable GL device (the GlUnavailableError
    /// message; GpuLevels::Auto then runs the CPU path) or GpuLevels::Never (no context is opened at all).
    std::string gpuUnavailable;
    std::size_t objects = 0;
    std::size_t triangles = 0;
    std::size_t rejectedObjects = 0;
    std::size_t prepassObjectsIn = 0;   ///< objects entering the CPU box pre-pass
    std::size_t prepassObjectsOut = 0;  ///< objects whose box overlaps another object's box
    /// Clusters the GPU levels ran on (objects that can meet, each with its own views and upload origin).
    std::size_t clusters = 0;
    /// ... of which too large for float coordinates (extent above 1e30): their triangles went to the exact stage.
    std::size_t unrasterisedClusters = 0;
    /// GL back-end, Pipeline::Auto: clusters whose two levels ran again because the group level, run ahead without
    /// waiting, or the triangle level, deferred to the frame's read-back, stopped early on the device (its records
    /// needed building again, or it needed more iterations than the level in its place ran before); the second time
    /// they are waited for. The results are the same; `levels` lists the second attempt, the frame's totals (draws,
    /// bytes, read-backs) both.
    std::size_t levelReruns = 0;
    std::size_t prepassGroupsIn = 0;   ///< groups of k triangles entering the pre-pass (0 without GPU levels:
    std::size_t prepassGroupsOut = 0;  ///< that path filters triangles directly)
    std::vector<LevelStats> levels;
    std::size_t pcsObjects = 0;
    std::size_t candidateObjectPairs = 0;
    /// Pairs whose inflated boxes overlap (handed to the exact test); with the device exact stage, those it did not
    /// certify apart.
    std::size_t candidateTrianglePairs = 0;
    std::size_t exactTests = 0;
    /// The exact stage's box trees (one per mesh with surviving triangles): built in a spatial order of the mesh kept
    /// between frames (a refit, no sort: when the survivors are at least an eighth of the mesh), or sorted.
    std::size_t exactTreesRefit = 0;
    std::size_t exactTreesSorted = 0;
    /// The CPU path's box trees of all of a mesh's triangles (in place of the two above for that mesh): built this
    /// frame straight from the vertices (a mesh lying mostly near its partners), or kept from an earlier frame (a
    /// static mesh, Object::staticKey: built once).
    std::size_t exactTreesWhole = 0;
    std::size_t exactTreesKept = 0;
    /// Spatial orders of whole meshes computed this frame (kept between frames; recomputed when a mesh's counts
    /// change or its version for the Object::staticKey the order was computed for, and every 16 frames for meshes
    /// without a key, or shared by instances with keys of their own).
    std::size_t meshOrdersComputed = 0;
    std::size_t intersectingTrianglePairs = 0;  ///< exact pairs found (0 with Settings::exactTriangles false)
    std::size_t draws = 0;
    /// The culler's worker pool this frame (TaskPool::Counters): parallel loops handed to the workers, sleeping
    /// workers a loop had to wake, and times the calling thread slept waiting for the workers. Each wake-up sits on
    /// a loop's critical path (costly on virtual machines); the frame wakes its workers at its start and they poll
    /// through its serial steps, so a steady frame should have none.
    std::size_t poolCalls = 0;
    std::size_t poolWorkerWakes = 0;
    std::size_t poolCallerSleeps = 0;
    /// GpuLevels::Auto with a hardware GL device: "measuring" (the first four frames of a scene, and again after its triangle
    /// count halved or doubled, at most once per 120 frames, alternate the CPU path and the GPU levels and time
    /// them; each trial that again finds one path at least twice as fast doubles that interval, up to 3,840 frames),
    /// then "gpu" or "cpu", the faster of the two. Empty where nothing was decided (GpuLevels::Always or
    /// Never, Pipeline::Paper, no device).
    std::string autoDecision;
    double autoCpuMs = 0.0;  ///< the timed trial frames behind autoDecision, whole-frame ms (0 until one is done)
    double autoGpuMs = 0.0;
    /// GPU trial frames whose levels ran past their budget (the last CPU trial frame plus 1 ms) and were finished on
    /// the CPU path: a trial never stalls a frame loop by more than about one CPU frame plus 1 ms.
    std::size_t autoTrialsAbandoned = 0;
    /// The frame ran past the budget of Culler::run(objects, only, result, budgetMs) and was abandoned: no pairs.
    bool abandoned = false;
    /// GPU levels abandoned this frame because of a GL error: the frame was finished on the CPU path instead (the
    /// same exact pairs: the GPU levels only prune; with exactTriangles false, more candidates), and gpuError says
    /// why. The next frame tries the GPU again.
    std::size_t gpuFallbacks = 0;
    std::size_t staticObjectsReused = 0;  ///< static meshes (Object::staticKey) whose checks and boxes were kept
    /// Keyed meshes whose transform changed since their last frame: their checks in their own frame were kept (and,
    /// when GPU levels run the Auto pipeline, their groups' boxes there), not their world boxes.
    std::size_t movingObjectsReused = 0;
    std::string gpuError;
    std::size_t bytesUploaded = 0;
    /// What the culler holds on its GL device after the frame: buffer capacities plus the view images.
    std::size_t gpuDeviceBytes = 0;
    std::size_t bytesReadBack = 0;
    /// The device exact stage (Settings::deviceExact): clusters whose candidate pairs the device found, the pairs it
    /// wrote (those its filter did not certify apart), those it certified intersecting (the others went to the CPU's
    /// exact predicate), and clusters whose pairs overflowed the device's buffer (their exact stage ran on the CPU;
    /// the buffer grows for the next frame).
    std::size_t deviceExactClusters = 0;
    std::size_t deviceExactPairs = 0;
    std::size_t deviceExactCertified = 0;
    std::size_t deviceExactOverflows = 0;
    /// Read-backs this frame that waited for the device to finish the work submitted before (the sum over levels,
    /// unless a level ran again): each is a round trip that leaves the device idle until the CPU submits again. One
    /// in a steady frame of the Auto pipeline, however many clusters it has (a cluster whose group level ends on the
    /// CPU waits for its triangle level on its own).
    std::size_t blockingReadBacks = 0;
    double prepassMs = 0.0;
    double uploadMs = 0.0;
    double gpuLevelsMs = 0.0;  ///< wall time of all GPU levels (0 when none ran: that CPU work is in prepassMs)
    double gpuMs = 0.0;        ///< GPU time from timer queries, all levels and uploads; only with gpuTimingValid
    /// Of gpuMs, the uploads' (their transfers, and the dispatches that map the transformed meshes and build the
    /// groups' boxes), each a span of its own read after the next blocking read-back. 0 without GPU levels or where
    /// gpuTimingValid is false.
    double uploadGpuMs = 0.0;
    /// false when some GPU level's or upload's timing is absent (LevelStats::gpuTimingValid): gpuMs is then 0, not a
    /// time.
    /// true (gpuMs 0) in frames without GPU levels.
    bool gpuTimingValid = true;
    double exactMs = 0.0;
    double totalMs = 0.0;
};

}  // namespace cullide
