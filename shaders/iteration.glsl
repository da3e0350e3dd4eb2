// The end of an iteration, shared by the compute back-end's flag pass (flag.comp) and the raster back-end's survivor
// pass (survive.comp), which decide the fate of each item alive at the iteration's start:
//   - an item that is not hidden in every enabled view leaves the set (nothing leaves when an invocation overflowed
//     or the records did not fit their buffers): its alive bit is cleared;
//   - the items still alive are counted, their owner range and bounds gathered: per work group first (shared-memory
//     atomics), then one global atomic per counter and group;
//   - the last work group to finish ends the iteration as VisibilityLevel.cpp's loop does on the CPU
//     (finishIteration): it records what the iteration left, decides whether the level goes on and, if so, fits the
//     next view and writes the next iteration's indirect arguments; otherwise it writes empty ones, so the iterations
//     the C++ side issued beyond the last dispatch nothing.
// Needs view.glsl, passes.glsl, common.glsl (alive, owners, u_resolution), visit.glsl (flags) and gather.glsl before
// it.
layout(std430, binding = CULLIDE_SSBO_ITEM_BOUNDS) coherent buffer Bounds { uint bounds[]; };  // and record counts
layout(location = CULLIDE_LOC_ITEM_COUNT) uniform uint u_itemCount;
layout(location = CULLIDE_LOC_REQUIRED) uniform uint u_required;
layout(location = CULLIDE_LOC_MAX_ITERATIONS) uniform uint u_maxIterations;
layout(location = CULLIDE_LOC_MIN_PRUNE_FRACTION) uniform double u_minPruneFraction;

shared bool s_last;

// Whether an item alive at the iteration's start stays alive. Every pass counts the invocations over its limit, so the
// flag pass reads the nearest pass's count: final before any item is decided.
bool staysAlive(uint item) {
    bool hidden = (flags[item] & u_required) == u_required;
    bool prunes = counters[CULLIDE_COUNTER_OVERFLOWS] == 0u && counters[CULLIDE_DISPATCH_SHORT] == 0u;
    return hidden || !prunes;
}

// VisibilityPass.cpp's recordsStale: the view has shrunk to a quarter of the one the records were built for along
// some axis (each record's bands grow with the square of it).
bool recordsStale(uint next) {
    uint built = counters[CULLIDE_CHAIN_RECORDED_VIEW];
    for (int a = 0; a < 3; ++a) {
        precise double now = views[next].boxMax[a] - views[next].boxMin[a];
        precise double then = views[built].boxMax[a] - views[built].boxMin[a];
        if (4.0lf * now < then) return true;
    }
    return false;
}

// An item alive at the iteration's start, once all of its flags are in: it stays (counted in the work group's
// counters) or leaves the set.
void decideItem(uint item) {
    if (!staysAlive(item)) {
        alive[item] = 0u;
        atomicAnd(counters[CULLIDE_ALIVE_BITS + item / 32u], ~(1u << (item % 32u)));
        atomicAdd(s_counters[CULLIDE_COUNTER_PRUNED], 1u);
        return;
    }
    uint top = 3u * (u_itemCount + item);
    gatherAlive(owners[item], uvec3(bounds[3u * item], bounds[3u * item + 1u], bounds[3u * item + 2u]),
                uvec3(bounds[top], bounds[top + 1u], bounds[top + 2u]));
}

// Whether this work group is the dispatch's last to finish (every lane calls it): what every group wrote before the
// call is visible to the last one.
bool lastGroupToFinish() {
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationID.x == 0u) {
        uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z;
        s_last = atomicAdd(counters[CULLIDE_CHAIN_SURVIVE_DONE], 1u) == groups - 1u;
    }
    barrier();
    memoryBarrierBuffer();
    return s_last;
}

// The end of iteration u_iteration (the last work group, one lane): what it left, the stop rule of
// VisibilityLevel.cpp's stepAfter in the same order, the next view, and the next iteration's arguments (empty when
// the chain stops): its passes over `nextRecords` records, its survivor pass (raster back-end) over `surviveOver`
// invocations. `ranOver`: the records this iteration's passes ran over (those of items alive at its start).
void finishIteration(uint ranOver, uint nextRecords, uint surviveOver) {
    uint it = u_iteration;
    uint left = counters[CULLIDE_COUNTER_ALIVE];
    uint overflows = counters[CULLIDE_COUNTER_OVERFLOWS];
    uint ownerMin = counters[CULLIDE_COUNTER_OWNER_MIN];
    uint ownerMax = counters[CULLIDE_COUNTER_OWNER_MAX];
    uint before = it == 0u ? counters[CULLIDE_CHAIN_ALIVE_START] : counters[CULLIDE_CHAIN_ALIVE + it - 1u];
    bool shortBuild = counters[CULLIDE_DISPATCH_SHORT] != 0u;
    // Every item alive at the start is decided exactly once, except in a short iteration (no record ran: nothing
    // leaves, and the C++ side runs it again).
    if (shortBuild) left = before;
    bool miscounted = !shortBuild && left + counters[CULLIDE_COUNTER_PRUNED] != before;
    if (miscounted) counters[CULLIDE_CHAIN_MISCOUNTED] = 1u;
    uint stop = CULLIDE_STOP_NONE;
    if (overflows != 0u || shortBuild || miscounted || left == before || left == 0u)
        stop = CULLIDE_STOP_DONE;
    else if (ownerMin == ownerMax)
        stop = CULLIDE_STOP_ONE_OWNER;
    else if (double(before - left) < u_minPruneFraction * double(before))
        stop = CULLIDE_STOP_DONE;
    else if (it + 1u >= u_maxIterations)
        stop = CULLIDE_STOP_DONE;
    if (stop == CULLIDE_STOP_NONE) {
        fitView(it + 1u, ownerMax, u_resolution);
        if (recordsStale(it + 1u)) stop = CULLIDE_STOP_REFIT;
    }
    views[it].alive = left;
    views[it].ownerMin = ownerMin;
    views[it].ownerMax = ownerMax;
    views[it].overflows = overflows;
    views[it].records = ranOver;
    views[it].stop = stop;
    for (int a = 0; a < 3; ++a) {
        views[it].boundsLo[a] = counters[CULLIDE_COUNTER_LO + a];
        views[it].boundsHi[a] = counters[CULLIDE_COUNTER_HI + a];
    }
    counters[CULLIDE_CHAIN_ALIVE + it] = left;
    counters[CULLIDE_CHAIN_RAN] = it + 1u;
    counters[CULLIDE_CHAIN_STOP] = stop;
    counters[CULLIDE_CHAIN_RECORDS_RUN] += ranOver;
    counters[CULLIDE_CHAIN_SURVIVE_DONE] = 0u;
    bool goesOn = stop == CULLIDE_STOP_NONE;
    writePassArguments(goesOn ? nextRecords : 0u, goesOn ? surviveOver : 0u, goesOn);
}

