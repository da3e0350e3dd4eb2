// The level's records, built on the device: at the level's start, and again where the view shrank enough to refit
// the bands (VisibilityPass.cpp). A record is (primitive reference, item, band, bands); on the compute back-end each
// primitive of an alive item is split into bands of its largest footprint over the three views, so that no
// invocation of the compute back-end's passes (scan.glsl) scans more than CULLIDE_PIXELS_PER_INVOCATION pixels. The
// passes of this program (CULLIDE_LOC_PASS), one invocation per primitive of the level's items (alive or not; a
// primitive finds its item by binary search: an item of a whole mesh has too many primitives for one invocation's
// loops):
//   FOOTPRINTS  each primitive's footprint and each work group's sum; the last work group to finish turns the sum
//               over all of them into the pixels per band (short bands: a hardware GPU's load balance). At the
//               level's start (CULLIDE_LOC_WITH_BOUNDS) also each primitive's box into its item's, for iteration.glsl.
//   APPEND      each primitive's records (none for a pruned item's), appended where its work group reserved room
//               with one atomic add, and counted in its item's (CULLIDE_SSBO_ITEM_BOUNDS); the last work group to
//               finish turns the total into the count and the indirect arguments of the iteration's record-sized
//               passes (CULLIDE_DISPATCH_*): the C++ side never waits.
//   SINGLE      both in one pass where the pixels per band are given (CULLIDE_LOC_PER_BAND): long bands on a software
//               renderer, or short bands estimated from the last build in the level's place (whose sum this pass
//               leaves for the next one, CULLIDE_CHAIN_PER_BAND) — or where there are no bands (the raster
//               back-end). A build is one dispatch there; only a place's first short-band build takes two.
// A build runs over the items alive: all of them at a level's start, or those start.comp marked (a level described by
// its objects, whose primitives and owners start.comp also wrote).
// A work group whose records would not fit the buffers' capacity writes none: the build is then short, the iteration
// runs over no record and prunes nothing, and the C++ side, which reads the needed total with the iteration's
// counters, grows the buffers and builds again. The records come out in no particular order: every pass over them is
// order-independent (atomic min, max and or).
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_ALIVE) readonly buffer Alive { uint alive[]; };
layout(std430, binding = CULLIDE_SSBO_PRIM_BEGIN) readonly buffer PrimBegin { uint primBegin[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_PRIMS) readonly buffer ItemPrims { uint itemPrims[]; };
layout(std430, binding = CULLIDE_SSBO_BANDS) buffer Bands { uint bands[]; };
layout(std430, binding = CULLIDE_SSBO_BUILD) coherent buffer Build { uint build[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS) writeonly buffer Prims { uvec4 prims[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_BOUNDS) buffer Bounds { uint bounds[]; };

layout(location = CULLIDE_LOC_PASS) uniform int u_pass;
layout(location = CULLIDE_LOC_PRIM_COUNT) uniform uint u_primCount;  // of the level's items, all of them
layout(location = CULLIDE_LOC_PRIM_BASE) uniform uint u_primBase;
layout(location = CULLIDE_LOC_ITEM_COUNT) uniform uint u_itemCount;
layout(location = CULLIDE_LOC_BANDS) uniform int u_bands;
layout(location = CULLIDE_LOC_GROUPS) uniform uint u_groups;
layout(location = CULLIDE_LOC_CAPACITY) uniform uint u_capacity;
layout(location = CULLIDE_LOC_WITH_BOUNDS) uniform int u_withBounds;
layout(location = CULLIDE_LOC_ONE_PRIM_EACH) uniform int u_onePrimEach;
layout(location = CULLIDE_LOC_PER_BAND) uniform float u_perBand;

const uint kLanes = uint(CULLIDE_COMPUTE_GROUP_SIZE);
shared uint s_scan[CULLIDE_COMPUTE_GROUP_SIZE];
shared float s_sum[CULLIDE_COMPUTE_GROUP_SIZE];
shared uint s_base;   // APPEND: where the work group's records start
shared uint s_total;  // APPEND: the work group's records
shared bool s_last;
shared uint s_runItem[CULLIDE_COMPUTE_GROUP_SIZE];  // APPEND, SINGLE: per lane, the item its records go to (or none)

// Inclusive prefix sum over the work group's lanes (every lane must call it).
uint inclusiveScan(uint value) {
    uint lane = gl_LocalInvocationID.x;
    s_scan[lane] = value;
    barrier();
    for (uint offset = 1u; offset < kLanes; offset <<= 1u) {
        uint before = lane >= offset ? s_scan[lane - offset] : 0u;
        barrier();
        s_scan[lane] += before;
        barrier();
    }
    uint sum = s_scan[lane];
    barrier();
    return sum;
}

// Sum over the work group's lanes, returned to every lane (every lane must call it).
float groupSum(float value) {
    uint lane = gl_LocalInvocationID.x;
    s_sum[lane] = value;
    barrier();
    for (uint stride = kLanes / 2u; stride > 0u; stride >>= 1u) {
        if (lane < stride) s_sum[lane] += s_sum[lane + stride];
        barrier();
    }
    float sum = s_sum[0];
    barrier();
    return sum;
}

// Whether this work group is the last of the pass's u_groups to finish (every lane must call it): each group's writes
// before the call are visible to the last one.
bool lastToFinish(uint doneCounter, bool inBuild) {
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationID.x == 0u) {
        uint done = inBuild ? atomicAdd(build[doneCounter], 1u) : atomicAdd(counters[doneCounter], 1u);
        s_last = done == u_groups - 1u;
    }
    barrier();
    memoryBarrierBuffer();
    return s_last;
}

vec3 primExtent(uint ref) {
    vec3 lo;
    vec3 hi;
    primBox(ref, lo, hi);
    return hi - lo;
}

// Pixels of the largest of a primitive's three footprints: its bounding rectangle grown by the tested square and a
// pixel of rounding on each side. The three views are written out (no loop over vector components).
float footprintOf(vec3 size) {
    ViewRecord v = views[u_iteration];
    vec3 pixelScale = vec3(v.pixelScale[0], v.pixelScale[1], v.pixelScale[2]);
    vec3 halfSize = vec3(v.halfSize[0], v.halfSize[1], v.halfSize[2]);
    vec3 side = size * pixelScale + 2.0 * halfSize + vec3(3.0);
    return max(max(side.y * side.z, side.z * side.x), side.x * side.y);
}

// Work group `group`'s footprints, summed (every lane calls it), for shortBandsPerBand.
void addGroupFootprints(uint group, float pixels) {
    float sum = groupSum(pixels);
    if (gl_LocalInvocationID.x == 0u) build[CULLIDE_BUILD_GROUPS + group] = floatBitsToUint(sum);
}

// The last work group (every lane calls it): the pixels per band of short bands from every group's footprints, for
// about CULLIDE_TARGET_INVOCATIONS records (a hardware GPU's load balance), also left in the chain
// (CULLIDE_CHAIN_PER_BAND: the next build in this level's place may take it as its estimate and build in one pass).
float shortBandsPerBand() {
    float total = 0.0;
    for (uint g = gl_LocalInvocationID.x; g < u_groups; g += kLanes)
        total += uintBitsToFloat(build[CULLIDE_BUILD_GROUPS + g]);
    total = groupSum(total);
    float perBand = float(CULLIDE_PIXELS_PER_INVOCATION);
    if (u_bands == CULLIDE_BANDS_SHORT)
        perBand = clamp(ceil(total / CULLIDE_TARGET_INVOCATIONS), CULLIDE_MIN_PIXELS_PER_INVOCATION, perBand);
    if (gl_LocalInvocationID.x == 0u) counters[CULLIDE_CHAIN_PER_BAND] = floatBitsToUint(perBand);
    return perBand;
}

// At most half of CULLIDE_MAX_LOOP_ITERATIONS bands, so that the APPEND pass's loop stays within llvmpipe's limit; a
// primitive that would need more gets longer bands, and scan.glsl counts an invocation over the limit as an overflow.
uint bandsOf(float footprint, float perBand) {
    return uint(clamp(ceil(footprint / perBand), 1.0, float(CULLIDE_MAX_LOOP_ITERATIONS / 2)));
}

// The count and indirect arguments of the record-sized passes over `total` records (none when they do not fit).
// `approx` (an upper bound that cannot wrap around) only rules out a total that wrapped around 2^32; total decides.
void writeDispatch(uint total, float approx) {
    bool fits = approx <= 2147483648.0 && total <= u_capacity;
    uint records = fits ? total : 0u;
    writePassArguments(records, max(records, u_itemCount), true);
    counters[CULLIDE_DISPATCH_NEEDED] = total;
    counters[CULLIDE_DISPATCH_NEEDED_APPROX] = floatBitsToUint(approx);
    counters[CULLIDE_DISPATCH_SHORT] = fits ? 0u : 1u;
}

// Primitive `prim`'s box into its item's, cleared by the C++ side (at the level's start). The axes are written out:
// NVIDIA's compiler (driver 580.159) crashed on a loop of atomics indexed by the loop variable (iteration.glsl).
void addToItemBounds(uint prim, uint item) {
    vec3 lo;
    vec3 hi;
    primBox(prim, lo, hi);
    uint at = 3u * item;
    uint top = 3u * (u_itemCount + item);
    atomicMin(bounds[at], orderedBits(lo.x));
    atomicMin(bounds[at + 1u], orderedBits(lo.y));
    atomicMin(bounds[at + 2u], orderedBits(lo.z));
    atomicMax(bounds[top], orderedBits(hi.x));
    atomicMax(bounds[top + 1u], orderedBits(hi.y));
    atomicMax(bounds[top + 2u], orderedBits(hi.z));
}

// The item primitive p belongs to: the last i with primBegin[i] <= p (binary search over the items).
uint itemOf(uint p) {
    if (u_onePrimEach != 0) return p;
    uint lo = 0u;
    uint hi = u_itemCount;  // primBegin[lo] <= p < primBegin[hi]
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (primBegin[mid] <= p) lo = mid; else hi = mid;
    }
    return lo;
}

// The records of the work group's run of lanes whose primitives belong to `item` (an item's primitives lie together),
// counted for the item with one atomic add by the run's first lane (`before`: the records of the lanes before it). A
// whole-mesh item has thousands of primitives: one add per lane would all hit one word.
void addItemRecords(uint item, uint before) {
    uint lane = gl_LocalInvocationID.x;
    if (lane > 0u && s_runItem[lane - 1u] == item) return;
    uint last = lane;
    while (last + 1u < kLanes && s_runItem[last + 1u] == item) ++last;
    atomicAdd(bounds[6u * u_itemCount + item], s_scan[last] - before);
}

void main() {
    uint lane = gl_LocalInvocationID.x;
    uint group = u_primBase / kLanes + gl_WorkGroupID.x;
    uint p = u_primBase + gl_GlobalInvocationID.x;
    uint item = p < u_primCount ? itemOf(p) : 0u;
    bool single = u_pass == CULLIDE_BUILD_PASS_SINGLE;
    bool live = p < u_primCount && alive[item] != 0u;
    uint prim = p < u_primCount ? itemPrims[p] : 0u;
    if (u_pass == CULLIDE_BUILD_PASS_FOOTPRINTS) {
        if (u_withBounds != 0 && p < u_primCount) addToItemBounds(prim, item);
        float pixels = live ? footprintOf(primExtent(prim)) : 0.0;
        if (p < u_primCount) bands[p] = floatBitsToUint(pixels);
        addGroupFootprints(group, pixels);
        if (!lastToFinish(CULLIDE_BUILD_FOOTPRINTS_DONE, true)) return;
        float perBand = shortBandsPerBand();
        if (lane == 0u) build[CULLIDE_BUILD_PER_BAND] = floatBitsToUint(perBand);
    } else {  // APPEND, SINGLE
        if (single && u_withBounds != 0 && p < u_primCount) addToItemBounds(prim, item);
        bool shortBands = u_bands == CULLIDE_BANDS_SHORT;
        float pixels = live && single && u_bands != CULLIDE_BANDS_NONE ? footprintOf(primExtent(prim)) : 0.0;
        if (single && shortBands) addGroupFootprints(group, pixels);
        uint n = 0u;
        if (live && u_bands == CULLIDE_BANDS_NONE) {
            n = 1u;
        } else if (live && single) {  // the pixels per band as given: long bands, or short ones estimated
            n = bandsOf(pixels, u_perBand);
        } else if (live) {
            n = bandsOf(uintBitsToFloat(bands[p]), uintBitsToFloat(build[CULLIDE_BUILD_PER_BAND]));
        }
        uint inclusive = inclusiveScan(n);
        if (lane == kLanes - 1u) {  // the group's total: room for it, and an upper bound in units of 256
            s_base = atomicAdd(counters[CULLIDE_DISPATCH_NEEDED], inclusive);
            atomicAdd(counters[CULLIDE_DISPATCH_NEEDED_HI], (inclusive + 255u) / 256u);
            s_total = inclusive;
        }
        s_runItem[lane] = n != 0u ? item : 0xFFFFFFFFu;
        barrier();
        uint base = s_base;
        uint groupTotal = s_total;
        bool fits = base + groupTotal >= base && base + groupTotal <= u_capacity;  // no wrap-around, within capacity
        uint record = base + inclusive - n;
        if (fits && n != 0u) {
            for (uint band = 0u; band < n; ++band) prims[record + band] = uvec4(prim, item, band, n);
            addItemRecords(item, inclusive - n);
        }
        if (!lastToFinish(CULLIDE_DISPATCH_BUILD_DONE, false)) return;
        if (single && shortBands) shortBandsPerBand();  // for the next build's estimate
        if (lane == 0u) {
            uint total = atomicAdd(counters[CULLIDE_DISPATCH_NEEDED], 0u);
            float approx = float(atomicAdd(counters[CULLIDE_DISPATCH_NEEDED_HI], 0u)) * 256.0;
            writeDispatch(total, approx);
            counters[CULLIDE_CHAIN_RECORDED_VIEW] = u_iteration;
        }
    }
}
