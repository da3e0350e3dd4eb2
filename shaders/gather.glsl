// What the items alive gather — their count, owner range and bounds, per work group in shared memory, then one global
// atomic per counter and group — and the view fitted to them. Shared by an iteration's end (iteration.glsl: the
// survivors and the next view) and the start of a level described by its objects (start.comp: the items that start
// alive and the first view). Needs view.glsl and passes.glsl before it.
layout(location = CULLIDE_LOC_MARGIN) uniform double u_margin;
layout(location = CULLIDE_LOC_COORDINATE_BOUND) uniform double u_coordinateBound;

// The three axes are written out: NVIDIA's GLSL compiler (driver 580.159) crashes the process linking a program with a
// loop over shared and global counters indexed by the loop variable (found on an H100; docs/benchmarks.md).
shared uint s_counters[CULLIDE_COUNTER_COUNT];

// The work group's counters start empty (every lane calls it; a barrier must follow before they are added to).
void clearGroupCounters() {
    uint lane = gl_LocalInvocationID.x;
    if (lane >= uint(CULLIDE_COUNTER_COUNT)) return;
    bool minimum = lane == uint(CULLIDE_COUNTER_OWNER_MIN) || (lane >= uint(CULLIDE_COUNTER_LO) &&
                                                               lane < uint(CULLIDE_COUNTER_HI));
    s_counters[lane] = minimum ? 0xFFFFFFFFu : 0u;
}

// An item that is alive: counted in the work group's counters, with its owner and its box (lo, hi as order-preserving
// float bits).
void gatherAlive(uint owner, uvec3 lo, uvec3 hi) {
    atomicAdd(s_counters[CULLIDE_COUNTER_ALIVE], 1u);
    atomicMin(s_counters[CULLIDE_COUNTER_OWNER_MIN], owner);
    atomicMax(s_counters[CULLIDE_COUNTER_OWNER_MAX], owner);
    atomicMin(s_counters[CULLIDE_COUNTER_LO + 0], lo.x);
    atomicMin(s_counters[CULLIDE_COUNTER_LO + 1], lo.y);
    atomicMin(s_counters[CULLIDE_COUNTER_LO + 2], lo.z);
    atomicMax(s_counters[CULLIDE_COUNTER_HI + 0], hi.x);
    atomicMax(s_counters[CULLIDE_COUNTER_HI + 1], hi.y);
    atomicMax(s_counters[CULLIDE_COUNTER_HI + 2], hi.z);
}

// The work group's counters into the iteration's (one lane, after a barrier).
void addGroupCounters() {
    if (s_counters[CULLIDE_COUNTER_PRUNED] != 0u)
        atomicAdd(counters[CULLIDE_COUNTER_PRUNED], s_counters[CULLIDE_COUNTER_PRUNED]);
    if (s_counters[CULLIDE_COUNTER_ALIVE] == 0u) return;
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

double orderedToDouble(uint key) {
    uint bits = (key & 0x80000000u) != 0u ? (key & 0x7FFFFFFFu) : ~key;
    return double(uintBitsToFloat(bits));
}

double maxAbs(double a, double b) { return max(abs(a), abs(b)); }

// VisibilityLevel.cpp's fitView, operation for operation in double (precise: no fused multiply-add), into views[next]:
// the view of items whose bounds are (lo, hi) as the counters hold them, `resolution` pixels a side.
void fitView(uint next, uint ownerMax, int resolution) {
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
    precise double res = double(resolution);
    precise double bound = max(u_coordinateBound, max(max(maxAbs(bmin[0], bmax[0]), maxAbs(bmin[1], bmax[1])),
                                                      maxAbs(bmin[2], bmax[2])));
    for (int a = 0; a < 3; ++a) {
        precise double extent = bmax[a] - bmin[a];
        precise double relative = ldexp(1.0lf, -18) * (1.0lf + bound / extent);
        views[next].boxMin[a] = bmin[a];
        views[next].boxMax[a] = bmax[a];
        views[next].lo[a] = float(bmin[a]);
        // Each value in a precise temporary first: an expression stored straight into the buffer could be fused.
        precise double pixelScale = res / extent;
        precise double depthScale = 1.0lf / extent;
        precise double halfSize = 0.5lf + margin * res / extent + 1e-3lf + relative * res;
        precise double depthPad = margin / extent + relative + ldexp(1.0lf, -20);
        views[next].pixelScale[a] = float(pixelScale);
        views[next].depthScale[a] = float(depthScale);
        views[next].halfSize[a] = float(halfSize);
        views[next].depthPad[a] = float(depthPad);
    }
    // VisibilityLevel.cpp's idBitsFor
    uint bits = 1u;
    while (bits < 31u && (ownerMax >> bits) != 0u) ++bits;
    views[next].idBits = bits;
}

