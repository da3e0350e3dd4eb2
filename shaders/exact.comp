// The device exact stage, after a deferred triangle level described by its objects: the candidate triangle pairs among
// the level's survivors and the filter's verdict on each. Work is by group pair: invocation (group, chunk c), over the
// groups of triangles whose parent survived (start.comp lists them), runs where some triangle of the group survives.
// It compares its group's box with the group boxes of its range's exact partners (the ranges of the meshes it may
// meet, each object pair listed once) from partner item c * u_chunkItems on, and for each pair of groups whose boxes
// meet within u_slack, their surviving triangles through the alive set's bits (an item pruned costs a bit). It writes
// every triangle pair whose boxes meet within u_slack (the margin and the float error of the positions: a superset of
// the pairs whose double boxes, grown by margin / 2, overlap; a group's box holds its triangles') and that the filter
// does not certify apart — certified intersecting (CULLIDE_EXACT_WITHIN) or left to the CPU's exact predicate. The
// filter is DeviceExactFilter.h's, operation for operation: the reference backend runs that one and the lockstep tests
// hold the two to the same pairs and verdicts. No loop over the filter's axes (llvmpipe ends an invocation's loops
// after 65,535 iterations in all): each is written out; a chunk's group pairs stay within that (ExactRequest).
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_COUNTERS) readonly buffer Counters { uint counters[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_PRIMS) readonly buffer ItemPrims { uint itemPrims[]; };
layout(std430, binding = CULLIDE_SSBO_EXACT_ITEMS) readonly buffer ExactItems { uint exactItems[]; };
layout(std430, binding = CULLIDE_SSBO_EXACT) buffer ExactPairs { uint exactPairs[]; };
layout(location = CULLIDE_LOC_EXACT_PARTNERS) uniform uint u_partners;
layout(location = CULLIDE_LOC_SLACK) uniform float u_slack;
layout(location = CULLIDE_LOC_REACH) uniform float u_reach;
layout(location = CULLIDE_LOC_FILTER) uniform int u_filter;
layout(location = CULLIDE_LOC_EXACT_CAPACITY) uniform uint u_capacity;
layout(location = CULLIDE_LOC_GROUP_SIZE) uniform uint u_groupSize;
layout(location = CULLIDE_LOC_CHUNK_ITEMS) uniform uint u_chunkItems;

// Powers of two, written out (GLSL has no hex float literals): each decimal converts to the power exactly.
const float k2m10 = 0.0009765625;
const float k2m18 = 3.814697265625e-6;
const float k2m20 = 9.5367431640625e-7;
const float k2m22 = 2.384185791015625e-7;
const float k2m23 = 1.1920928955078125e-7;
const float k2m24 = 5.9604644775390625e-8;
const float k2m100 = 7.888609052210118e-31;
const float k2m120 = 7.52316384526264e-37;
const float k2m125 = 2.350988701644575e-38;
const float k2p36 = 68719476736.0;

// The filter's bounds (DeviceExactFilter.h, Bounds).
float g_m;
float g_delta;
float g_orientErr;

float maxAbs(vec3 a) { return max(max(abs(a.x), abs(a.y)), abs(a.z)); }

float dot3(vec3 a, vec3 b) {
    precise float d = a.x * b.x + a.y * b.y + a.z * b.z;
    return d;
}

vec3 cross3(vec3 a, vec3 b) {
    precise vec3 c = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return c;
}

void boundsOf(vec3 p0, vec3 p1, vec3 p2, vec3 p3, vec3 p4, vec3 p5, vec3 r1, vec3 r2, vec3 r3, vec3 r4, vec3 r5) {
    float pos = max(max(max(maxAbs(p0), maxAbs(p1)), max(maxAbs(p2), maxAbs(p3))), max(maxAbs(p4), maxAbs(p5)));
    float m = max(max(max(0.0, maxAbs(r1)), max(maxAbs(r2), maxAbs(r3))), max(maxAbs(r4), maxAbs(r5)));
    precise float e = pos * k2m23 + k2m125;
    precise float delta = (e + e) + m * k2m23;
    precise float md = (m + m) * (1.0 + k2m20);
    precise float dd = (delta + delta) + m * k2m22;
    precise float moved = 6.0 * dd * (3.0 * md * md + 3.0 * md * dd + dd * dd);
    precise float err = (moved + 48.0 * k2m24 * md * md * md) * (1.0 + k2m10) + k2m120;
    g_m = m;
    g_delta = delta;
    g_orientErr = err;
}

bool apartAlong(vec3 w, vec3 r1, vec3 r2, vec3 r3, vec3 r4, vec3 r5) {
    precise float errP = ((abs(w.x) + abs(w.y) + abs(w.z)) * (g_delta + g_m * k2m22) * (1.0 + k2m20) + k2m120) *
                         2.0;
    float p0 = dot3(vec3(0.0), w);
    float p1 = dot3(r1, w);
    float p2 = dot3(r2, w);
    float q0 = dot3(r3, w);
    float q1 = dot3(r4, w);
    float q2 = dot3(r5, w);
    float minA = min(min(p0, p1), p2);
    float maxA = max(max(p0, p1), p2);
    float minB = min(min(q0, q1), q2);
    float maxB = max(max(q0, q1), q2);
    precise float gap = max(minB - maxA, minA - maxB);
    precise float g = (gap * (1.0 - k2m22) - errP) * (1.0 - k2m22);
    if (!(g >= k2m100)) return false;
    if (u_reach == 0.0) return true;
    precise float rhs = u_reach * u_reach * dot3(w, w) * (1.0 + k2m18);
    if (!(rhs >= k2m100)) return false;
    precise float lhs = g * g;
    return lhs > rhs;
}

int signOf(float d) { return d > g_orientErr ? 1 : (d < -g_orientErr ? -1 : 0); }

float orient(vec3 p, vec3 q, vec3 s, vec3 t) {
    precise vec3 qp = q - p;
    precise vec3 sp = s - p;
    precise vec3 tp = t - p;
    return dot3(cross3(qp, sp), tp);
}

bool edgeCrosses(vec3 p, vec3 q, vec3 s0, vec3 s1, vec3 s2) {
    int o0 = signOf(orient(p, q, s0, s1));
    int o1 = signOf(orient(p, q, s1, s2));
    int o2 = signOf(orient(p, q, s2, s0));
    return o0 != 0 && o0 == o1 && o1 == o2;
}

bool crossesInside(vec3 t0, vec3 t1, vec3 t2, vec3 s0, vec3 s1, vec3 s2) {
    precise vec3 e1 = s1 - s0;
    precise vec3 e2 = s2 - s0;
    precise vec3 d0 = t0 - s0;
    precise vec3 d1 = t1 - s0;
    precise vec3 d2 = t2 - s0;
    vec3 n = cross3(e1, e2);
    int c0 = signOf(dot3(n, d0));
    int c1 = signOf(dot3(n, d1));
    int c2 = signOf(dot3(n, d2));
    return (c0 * c1 < 0 && edgeCrosses(t0, t1, s0, s1, s2)) || (c1 * c2 < 0 && edgeCrosses(t1, t2, s0, s1, s2)) ||
           (c2 * c0 < 0 && edgeCrosses(t2, t0, s0, s1, s2));
}

// DeviceExactFilter.h's filterTrianglePair: 0 apart, 1 uncertain, 2 within (intersecting).
uint verdict(vec3 p0, vec3 p1, vec3 p2, vec3 p3, vec3 p4, vec3 p5) {
    vec3 r0 = vec3(0.0);
    precise vec3 r1 = p1 - p0;
    precise vec3 r2 = p2 - p0;
    precise vec3 r3 = p3 - p0;
    precise vec3 r4 = p4 - p0;
    precise vec3 r5 = p5 - p0;
    boundsOf(p0, p1, p2, p3, p4, p5, r1, r2, r3, r4, r5);
    if (!(g_m <= k2p36)) return 1u;
    precise vec3 ea2 = r2 - r1;
    precise vec3 eb0 = r4 - r3;
    precise vec3 eb1 = r5 - r3;
    precise vec3 eb2 = r5 - r4;
    if (apartAlong(cross3(r1, r2), r1, r2, r3, r4, r5) || apartAlong(cross3(eb0, eb1), r1, r2, r3, r4, r5)) return 0u;
    if (apartAlong(cross3(r1, eb0), r1, r2, r3, r4, r5) || apartAlong(cross3(r1, eb1), r1, r2, r3, r4, r5) ||
        apartAlong(cross3(r1, eb2), r1, r2, r3, r4, r5))
        return 0u;
    if (apartAlong(cross3(r2, eb0), r1, r2, r3, r4, r5) || apartAlong(cross3(r2, eb1), r1, r2, r3, r4, r5) ||
        apartAlong(cross3(r2, eb2), r1, r2, r3, r4, r5))
        return 0u;
    if (apartAlong(cross3(ea2, eb0), r1, r2, r3, r4, r5) || apartAlong(cross3(ea2, eb1), r1, r2, r3, r4, r5) ||
        apartAlong(cross3(ea2, eb2), r1, r2, r3, r4, r5))
        return 0u;
    if (crossesInside(r0, r1, r2, r3, r4, r5) || crossesInside(r3, r4, r5, r0, r1, r2)) return 2u;
    return 1u;
}

// The alive set's bits of items first .. last - 1 within word w.
uint aliveBits(uint w, uint first, uint last) {
    uint bits = counters[CULLIDE_ALIVE_BITS + w];
    if (w * 32u < first) bits &= ~0u << (first - w * 32u);
    if (last - w * 32u < 32u) bits &= (1u << (last - w * 32u)) - 1u;
    return bits;
}

// Whether some item of first .. last - 1 is alive.
bool anyAlive(uint first, uint last) {
    for (uint w = first / 32u; w * 32u < last; ++w)
        if (aliveBits(w, first, last) != 0u) return true;
    return false;
}

// Every pair of a surviving triangle of items aFirst .. aLast - 1 and one of bFirst .. bLast - 1 whose boxes meet
// within u_slack and that the filter does not certify apart, appended.
void pairsOf(uint aFirst, uint aLast, uint bFirst, uint bLast) {
    for (uint wa = aFirst / 32u; wa * 32u < aLast; ++wa) {
        uint bitsA = aliveBits(wa, aFirst, aLast);
        while (bitsA != 0u) {
            uint i = wa * 32u + uint(findLSB(bitsA));
            bitsA &= bitsA - 1u;
            vec3 a0, a1, a2;
            triangleAt(itemPrims[i], a0, a1, a2);
            precise vec3 reachLo = min(min(a0, a1), a2) - vec3(u_slack);
            precise vec3 reachHi = max(max(a0, a1), a2) + vec3(u_slack);
            for (uint wb = bFirst / 32u; wb * 32u < bLast; ++wb) {
                uint bitsB = aliveBits(wb, bFirst, bLast);
                while (bitsB != 0u) {
                    uint item = wb * 32u + uint(findLSB(bitsB));
                    bitsB &= bitsB - 1u;
                    vec3 b0, b1, b2;
                    triangleAt(itemPrims[item], b0, b1, b2);
                    vec3 loB = min(min(b0, b1), b2);
                    vec3 hiB = max(max(b0, b1), b2);
                    if (!all(lessThanEqual(reachLo, hiB)) || !all(lessThanEqual(loB, reachHi))) continue;
                    uint v = u_filter != 0 ? verdict(a0, a1, a2, b0, b1, b2) : 1u;
                    if (v == 0u) continue;
                    if (exactPairs[0] >= 0x80000000u) continue;  // the count stays far from wrapping around
                    uint slot = atomicAdd(exactPairs[0], 1u);
                    if (slot >= u_capacity) continue;
                    exactPairs[1u + 2u * slot] = i;
                    exactPairs[2u + 2u * slot] = item | (v == 2u ? CULLIDE_EXACT_WITHIN : 0u);
                }
            }
        }
    }
}

void main() {
    // Dispatched indirectly (start.comp): rows of work groups over the groups it listed, one per chunk.
    uint slot = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                gl_LocalInvocationID.x;
    if (slot >= counters[CULLIDE_CHAIN_STARTED]) return;
    uint groupFirst = exactItems[slot];  // a group of triangles whose parent survived, by its first item
    uint r = rangeOf(groupFirst);
    uint begin = field(r, CULLIDE_RANGE_ITEM_BEGIN);
    uint group = (groupFirst - begin) / u_groupSize;
    uint groupLast = min(groupFirst + u_groupSize, begin + field(r, CULLIDE_RANGE_COUNT));
    if (!anyAlive(groupFirst, groupLast)) return;
    uint list = u_partners + u_rangeCount + 1u;
    uint groupBoxes = list + ranges[u_partners + u_rangeCount];  // after every range's partners
    uint box = 6u * (ranges[groupBoxes + r] + group);
    vec3 lo = vec3(boxes[box], boxes[box + 1u], boxes[box + 2u]);
    vec3 hi = vec3(boxes[box + 3u], boxes[box + 4u], boxes[box + 5u]);
    // Partner items windowLo .. windowHi - 1 of the concatenation of its partner ranges, group by group: a partner
    // group whose box misses this group's (grown by u_slack) holds no pair (the boxes hold their triangles').
    uint windowLo = gl_WorkGroupID.y * u_chunkItems;
    uint windowHi = windowLo + u_chunkItems;
    uint end = ranges[u_partners + r + 1u];
    uint at = 0u;  // partner items before range p, summed
    for (uint p = ranges[u_partners + r]; p < end && at < windowHi; ++p) {
        uint other = ranges[list + p];
        uint count = field(other, CULLIDE_RANGE_COUNT);
        uint from = max(at, windowLo);
        uint to = min(at + count, windowHi);
        uint otherBegin = field(other, CULLIDE_RANGE_ITEM_BEGIN);
        uint otherBox = ranges[groupBoxes + other];
        uint g = from < to ? (from - at) / u_groupSize : 0u;
        for (; from < to && g * u_groupSize < to - at; ++g) {
            if (!meetsGrownBox(lo, hi, otherBox + g, u_slack)) continue;
            uint first = otherBegin + max(from - at, g * u_groupSize);
            uint last = otherBegin + min(to - at, (g + 1u) * u_groupSize);
            pairsOf(groupFirst, groupLast, first, last);
        }
        at += count;
    }
}
