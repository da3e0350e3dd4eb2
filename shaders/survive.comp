// After an iteration's flag pass, in one dispatch over max(items, records) invocations (CULLIDE_DISPATCH_SURVIVE):
//   - item i: an alive item that is not hidden in every enabled view leaves the set (nothing leaves when an
//     invocation overflowed or the records did not fit their buffers): its alive bit is cleared. The items still
//     alive are counted, their owner range and bounds gathered.
//   - record i: kept, packed to the front of the other record buffer, when its item stays alive (in no particular
//     order: every pass is order-independent — atomic min, max and or). The next iteration runs on these only: a
//     record of a pruned item would still cost its lane's whole warp.
// Both halves decide an item's fate from its flags alone: every record in the list belongs to an item alive before
// this pass (the records of items pruned earlier were dropped then), so no invocation reads what another writes.
// The last work group to finish then ends the iteration as VisibilityLevel.cpp's loop does on the CPU (finishIteration
// below): it records what the iteration left, decides whether the level goes on and, if so, fits the next view and
// writes the next iteration's indirect arguments; otherwise it writes empty ones, so the iterations the C++ side
// issued beyond the last dispatch nothing.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_FLAGS) readonly buffer Flags { uint flags[]; };
layout(std430, binding = CULLIDE_SSBO_ALIVE) buffer Alive { uint alive[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_OWNER) readonly buffer Owners { uint owners[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_BOUNDS) readonly buffer Bounds { uint bounds[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS) readonly buffer Prims { uvec4 prims[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS_OUT) writeonly buffer PrimsOut { uvec4 primsOut[]; };
layout(location = CULLIDE_LOC_ITEM_COUNT) uniform uint u_itemCount;
layout(location = CULLIDE_LOC_REQUIRED) uniform uint u_required;
layout(location = CULLIDE_LOC_MAX_ITERATIONS) uniform uint u_maxIterations;
layout(location = CULLIDE_LOC_RESOLUTION) uniform int u_resolution;
layout(location = CULLIDE_LOC_MARGIN) uniform double u_margin;
layout(location = CULLIDE_LOC_COORDINATE_BOUND) uniform double u_coordinateBound;
layout(location = CULLIDE_LOC_MIN_PRUNE_FRACTION) uniform double u_minPruneFraction;

// Per work group first (shared-memory atomics), then one global atomic per counter and group. The three axes are
// written out: NVIDIA's GLSL compiler (driver 580.159) crashes the process linking this program when they are a
// loop over shared and global counters indexed by the loop variable (found on an H100; docs/benchmarks.md).
shared uint s_counters[CULLIDE_COUNTER_COUNT];
shared uint s_count;
shared uint s_first;
shared bool s_last;

// Whether an item alive before this pass stays alive.
bool staysAlive(uint item) {
    bool hidden = (flags[item] & u_required) == u_required;
    bool prunes = counters[CULLIDE_COUNTER_OVERFLOWS] == 0u && counters[CULLIDE_DISPATCH_SHORT] == 0u;
    return hidden || !prunes;
}

double orderedToDouble(uint key) {
    uint bits = (key & 0x80000000u) != 0u ? (key & 0x7FFFFFFFu) : ~key;
    return double(uintBitsToFloat(bits));
}

double maxAbs(double a, double b) { return max(abs(a), abs(b)); }

// VisibilityLevel.cpp's fitView, operation for operation in double (precise: no fused multiply-add), into views[next]:
// the view of items whose bounds are (lo, hi) as the counters hold them.
void fitView(uint next, uint ownerMax) {
    precise double bmin[3];
    precise double bmax[3];
    for (int a = 0; a < 3; ++a) {
        bmin[a] = orderedToDouble(counters[CULLIDE_COUNTER_LO + a]);
        bmax[a] = orderedToDouble(counters[CULLIDE_COUNTER_HI + a]);
    }
    precise double margin = 0.5lf * u_margin;
    precise double scale = max(max(max(bmax[0] - bmin[0], bmax[1] - bmin[1]), bmax[2] - bmin[2]), 1e-30lf);
    precise double largest = max(u_coordinateBound, max(max(maxAbs(bmin[0], bmax[0]), maxAbs(bmin[1], bmax[1])),
                                                       maxAbs(bmin[2], bmax[2])));
    precise double grow = margin + 1e-4lf * scale + ldexp(largest, -22);
    for (int a = 0; a < 3; ++a) {
        bmin[a] = bmin[a] - grow;
        bmax[a] = bmax[a] + grow;
    }
    precise double minExtent = max(1e-6lf * max(max(bmax[0] - bmin[0], bmax[1] - bmin[1]), bmax[2] - bmin[2]),
                                   1e-30lf);
    for (int a = 0; a < 3; ++a) {
        if (bmax[a] - bmin[a] < minExtent) {
            bmin[a] = bmin[a] - 0.5lf * minExtent;
            bmax[a] = bmax[a] + 0.5lf * minExtent;
        }
    }
    precise double res = double(u_resolution);
    precise double bound = max(u_coordinateBound, max(max(maxAbs(bmin[0], bmax[0]), maxAbs(bmin[1], bmax[1])),
                                                      maxAbs(bmin[2], bmax[2])));
    for (int a = 0; a < 3; ++a) {
        precise double extent = bmax[a] - bmin[a];
        precise double relative = ldexp(1.0lf, -18) * (1.0lf + bound / extent);
        views[next].boxMin[a] = bmin[a];
        views[next].boxMax[a] = bmax[a];
        views[next].lo[a] = float(bmin[a]);
        views[next].pixelScale[a] = float(res / extent);
        views[next].depthScale[a] = float(1.0lf / extent);
        views[next].halfSize[a] = float(0.5lf + margin * res / extent + 1e-3lf + relative * res);
        views[next].depthPad[a] = float(margin / extent + relative + ldexp(1.0lf, -20));
    }
    // VisibilityLevel.cpp's idBitsFor
    uint bits = 1u;
    while (bits < 31u && (ownerMax >> bits) != 0u) ++bits;
    views[next].idBits = bits;
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

// The end of iteration u_iteration (the last work group, one lane): what it left, the stop rule of
// VisibilityLevel.cpp's stepAfter in the same order, the next view, and the next iteration's arguments (empty when
// the chain stops).
void finishIteration() {
    uint it = u_iteration;
    uint left = counters[CULLIDE_COUNTER_ALIVE];
    uint overflows = counters[CULLIDE_COUNTER_OVERFLOWS];
    uint ownerMin = counters[CULLIDE_COUNTER_OWNER_MIN];
    uint ownerMax = counters[CULLIDE_COUNTER_OWNER_MAX];
    uint ranOver = counters[CULLIDE_DISPATCH_RECORDS];
    uint before = it == 0u ? counters[CULLIDE_CHAIN_ALIVE_START] : counters[CULLIDE_CHAIN_ALIVE + it - 1u];
    uint stop = CULLIDE_STOP_NONE;
    if (overflows != 0u || counters[CULLIDE_DISPATCH_SHORT] != 0u || left == before || left == 0u)
        stop = CULLIDE_STOP_DONE;
    else if (ownerMin == ownerMax)
        stop = CULLIDE_STOP_ONE_OWNER;
    else if (double(before - left) < u_minPruneFraction * double(before))
        stop = CULLIDE_STOP_DONE;
    else if (it + 1u >= u_maxIterations)
        stop = CULLIDE_STOP_DONE;
    if (stop == CULLIDE_STOP_NONE) {
        fitView(it + 1u, ownerMax);
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
    uint next = stop == CULLIDE_STOP_NONE ? counters[CULLIDE_COUNTER_RECORDS] : 0u;
    writePassArguments(next, stop == CULLIDE_STOP_NONE ? max(next, u_itemCount) : 0u);
}

void main() {
    uint lane = gl_LocalInvocationID.x;
    if (lane < uint(CULLIDE_COUNTER_COUNT)) {
        bool minimum = lane == uint(CULLIDE_COUNTER_OWNER_MIN) || (lane >= uint(CULLIDE_COUNTER_LO) &&
                                                                   lane < uint(CULLIDE_COUNTER_HI));
        s_counters[lane] = minimum ? 0xFFFFFFFFu : 0u;
    }
    if (lane == 0u) s_count = 0u;
    barrier();
    uint i = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + lane;
    if (i < u_itemCount && alive[i] != 0u) {
        if (!staysAlive(i)) {
            alive[i] = 0u;
            atomicAnd(counters[CULLIDE_ALIVE_BITS + i / 32u], ~(1u << (i % 32u)));
        } else {
            atomicAdd(s_counters[CULLIDE_COUNTER_ALIVE], 1u);
            atomicMin(s_counters[CULLIDE_COUNTER_OWNER_MIN], owners[i]);
            atomicMax(s_counters[CULLIDE_COUNTER_OWNER_MAX], owners[i]);
            atomicMin(s_counters[CULLIDE_COUNTER_LO + 0], bounds[3u * i + 0u]);
            atomicMin(s_counters[CULLIDE_COUNTER_LO + 1], bounds[3u * i + 1u]);
            atomicMin(s_counters[CULLIDE_COUNTER_LO + 2], bounds[3u * i + 2u]);
            atomicMax(s_counters[CULLIDE_COUNTER_HI + 0], bounds[3u * (u_itemCount + i) + 0u]);
            atomicMax(s_counters[CULLIDE_COUNTER_HI + 1], bounds[3u * (u_itemCount + i) + 1u]);
            atomicMax(s_counters[CULLIDE_COUNTER_HI + 2], bounds[3u * (u_itemCount + i) + 2u]);
        }
    }
    uvec4 record = uvec4(0u);
    bool keep = false;
    if (i < counters[CULLIDE_DISPATCH_RECORDS]) {
        record = prims[i];
        keep = staysAlive(record.y);
    }
    uint slot = keep ? atomicAdd(s_count, 1u) : 0u;
    barrier();
    if (lane == 0u && s_count != 0u) s_first = atomicAdd(counters[CULLIDE_COUNTER_RECORDS], s_count);
    if (lane == 0u && s_counters[CULLIDE_COUNTER_ALIVE] != 0u) {
        atomicAdd(counters[CULLIDE_COUNTER_ALIVE], s_counters[CULLIDE_COUNTER_ALIVE]);
        atomicMin(counters[CULLIDE_COUNTER_OWNER_MIN], s_counters[CULLIDE_COUNTER_OWNER_MIN]);
        atomicMax(counters[CULLIDE_COUNTER_OWNER_MAX], s_counters[CULLIDE_COUNTER_OWNER_MAX]);
        atomicMin(counters[CULLIDE_COUNTER_LO + 0], s_counters[CULLIDE_COUNTER_LO + 0]);
        atomicMin(counters[CULLIDE_COUNTER_LO + 1], s_counters[CULLIDE_COUNTER_LO + 1]);
        atomicMin(counters[CULLIDE_COUNTER_LO + 2], s_counters[CULLIDE_COUNTER_LO + 2]);
        atomicMax(counters[CULLIDE_COUNTER_HI + 0], s_counters[CULLIDE_COUNTER_HI + 0]);
        atomicMax(counters[CULLIDE_COUNTER_HI + 1], s_counters[CULLIDE_COUNTER_HI + 1]);
        atomicMax(counters[CULLIDE_COUNTER_HI + 2], s_counters[CULLIDE_COUNTER_HI + 2]);
    }
    barrier();
    if (keep) primsOut[s_first + slot] = record;
    memoryBarrierBuffer();
    barrier();
    if (lane == 0u) {
        uint done = atomicAdd(counters[CULLIDE_CHAIN_SURVIVE_DONE], 1u);
        s_last = done == gl_NumWorkGroups.x * gl_NumWorkGroups.z - 1u;
    }
    barrier();
    memoryBarrierBuffer();
    if (s_last && lane == 0u) finishIteration();
}
