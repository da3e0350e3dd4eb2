// Culler settings. Every field is validated by validate(); the culler factory rejects invalid settings.
#pragma once

#include <cstddef>
#include <string>

namespace cullide {

enum class Mode {
    /// Never misses an intersecting (or within-margin) triangle pair at any resolution: conservative coverage,
    /// conservative depth, bounded float error (see docs/reliability.md).
    Reliable,
    /// The paper's plain rasterization at pixel centres: may miss contacts below pixel size.
    Sampled,
};

enum class Pipeline {
    /// Cheapest path that keeps the guarantee: CPU box pre-pass over objects and groups, group boxes on the GPU,
    /// then triangles of surviving groups; levels stop when the exact stage is cheaper.
    Auto,
    /// The paper's pipeline: GPU object level (boxes, then triangles), sub-objects drawn as triangles, triangles.
    /// It always runs its GPU levels (whatever Settings::gpuLevels says, except that validate() rejects it with
    /// GpuLevels::Never), so it needs a GL device: createGpuCuller throws GlUnavailableError without one.
    Paper,
};

enum class Backend {
    /// A compute shader scans each primitive's conservative footprint (default: multi-threaded on llvmpipe, and it
    /// avoids the fixed-function path on data-centre GPUs).
    Compute,
    /// The same test through the rasterizer (a vertex + fragment shader, three views side by side in one target).
    Raster,
};

enum class GpuLevels {
    /// Run the GPU visibility levels where they pay, by measurement, on a hardware GL device: the first four frames
    /// of a scene (and again when its triangle count halves or doubles, at most once per 120 frames, or less often
    /// while the same path keeps winning by at least twice) alternate the CPU path and the GPU levels, and the faster
    /// runs from then on (Stats::autoDecision, autoCpuMs, autoGpuMs). A GPU trial frame that runs past the last CPU
    /// frame's time plus 1 ms is finished on the CPU path (Stats::autoTrialsAbandoned), and a CPU trial frame is
    /// skipped where it would take more than twice a GPU frame plus 1 ms: no trial stalls a frame loop. Results are
    /// identical either way (with Settings::exactTriangles false the candidate supersets differ). On a software
    /// renderer (Mesa's llvmpipe) or without a GL device: the CPU path, with no GL context opened.
    Auto,
    /// Always run the GPU levels (tests, benchmarks, the paper-faithful pipeline).
    Always,
    /// Never run them: CPU box pre-passes and the exact stage only. Pipeline::Paper with Never is contradictory:
    /// validate() rejects it.
    Never,
};

/// Where the exact stage's candidate pairs are found when GPU levels run (Settings::deviceExact). On the device: after
/// each deferred triangle level, every pair of surviving triangles of two partner meshes whose boxes meet, and a
/// floating-point filter with certified error bounds decides those it can (apart, or intersecting); the CPU's exact
/// predicate decides the rest. On the CPU: box trees over the surviving triangles (ExactStage).
enum class DeviceExact {
    /// On the device where it is a hardware one; on a software renderer the CPU's box trees are faster (its
    /// all-pairs search per partner group runs on the CPU there).
    OnHardware,
    Always,  ///< on the device, a software renderer too (tests)
    Never,   ///< on the CPU
};

struct Settings {
    Mode mode = Mode::Reliable;
    Pipeline pipeline = Pipeline::Auto;
    Backend backend = Backend::Compute;
    GpuLevels gpuLevels = GpuLevels::Auto;
    /// Image-space resolution per view (square), 16..4096.
    int resolution = 256;
    /// Sub-object group size k (triangles per group), 1..4096.
    int groupSize = 32;
    /// View axes used by the visibility levels, a bit mask (1 = x, 2 = y, 4 = z), 1..7. Each enabled axis is viewed
    /// from both sides; an item is pruned when it is fully visible from any of those views.
    unsigned axes = 7;
    /// Maximum pruning iterations per level (each iteration draws all three axes, both directions), 1..64.
    int maxIterations = 4;
    /// An iteration that prunes less than this fraction of the items it started with ends its level, 0..1: the next
    /// one would prune fewer still, at the cost of a whole iteration. 0: a level iterates until its set stops changing
    /// or maxIterations. The exact stage decides the pairs either way: only the candidate set grows a little.
    double minPruneFraction = 0.0625;
    /// Distance margin d >= 0: triangle pairs closer than d are reported as well.
    double margin = 0.0;
    /// true: ObjectPair::triangles are the exactly intersecting (within-margin) pairs. false: the exact test is left
    /// to the caller's own narrow phase and ObjectPair::triangles lists every surviving candidate pair (triangle
    /// boxes grown by margin / 2 overlap) — a superset, cheaper to produce; the Bullet adapter uses this, since
    /// Bullet's triangle routines decide the contacts anyway. The reference culler is always exact.
    bool exactTriangles = true;
    /// With GPU levels: where the exact stage's candidate pairs are found (DeviceExact). The pairs are the same
    /// either way.
    DeviceExact deviceExact = DeviceExact::OnHardware;
    /// Worker threads for the CPU stages; 0 = the CPUs this process may run on (its affinity mask on Linux).
    unsigned threads = 0;
    /// Auto pipeline: a level whose input has at most this many triangles goes straight to the exact stage.
    std::size_t exactThreshold = 256;
    /// GL device to use: "" = environment variable CULLIDE_GL_DEVICE, else the first hardware device, else
    /// Mesa's software device / surfaceless platform. Also "software", "hardware", "surfaceless" or a device index
    /// "0", "1", ... (up to 4 digits); anything else fails validate(). An index no device has falls back to the CPU
    /// path with a notice, as a missing device does.
    std::string device;

    /// Empty string when valid, else a message naming the offending field.
    std::string validate() const;
};

}  // namespace cullide
