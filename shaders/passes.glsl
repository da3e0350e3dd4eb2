// The counter buffer and the indirect arguments of an iteration's record-sized passes (CULLIDE_DISPATCH_*), written
// on the device by build.comp after a record build and by the work group that ends an iteration (iteration.glsl):
// the C++ side never writes them.
layout(std430, binding = CULLIDE_SSBO_COUNTERS) coherent buffer Counters { uint counters[]; };
layout(location = CULLIDE_LOC_MAX_GROUPS) uniform uint u_maxGroups;

// Indirect arguments of a grid of at least `count` invocations: work groups along x, as many rows of them along z
// as needed (none for none).
void writeGrid(int slot, uint count, uint layers) {
    uint groups = (count + uint(CULLIDE_COMPUTE_GROUP_SIZE) - 1u) / uint(CULLIDE_COMPUTE_GROUP_SIZE);
    uint x = min(groups, u_maxGroups);
    counters[slot] = x;
    counters[slot + 1] = layers;
    counters[slot + 2] = x == 0u ? 0u : (groups + x - 1u) / x;
}

// The next iteration runs (`runs`; otherwise it dispatches nothing) its visibility passes over `records` records
// (three views each; at least one work group, whose flag pass ends the iteration on the compute back-end) and its
// survivor pass (raster back-end) over `surviveOver` invocations.
void writePassArguments(uint records, uint surviveOver, bool runs) {
    counters[CULLIDE_DISPATCH_RECORDS] = records;
    writeGrid(CULLIDE_DISPATCH_CULL, runs ? max(records, 1u) : 0u, 3u);
    writeGrid(CULLIDE_DISPATCH_SURVIVE, surviveOver, 1u);
    counters[CULLIDE_DISPATCH_DRAW] = 9u * records;
    counters[CULLIDE_DISPATCH_DRAW + 1] = 1u;
    counters[CULLIDE_DISPATCH_DRAW + 2] = 0u;
    counters[CULLIDE_DISPATCH_DRAW + 3] = 0u;
}
