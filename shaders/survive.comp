// After an iteration's flag pass, in one dispatch over max(items, records) invocations (CULLIDE_DISPATCH_SURVIVE):
//   - item i: an alive item that is not hidden in every enabled view leaves the set (nothing leaves when an
//     invocation overflowed or the records did not fit their buffers). The items still alive are counted, their
//     owner range and bounds gathered (to fit the next iteration's view) and their bits set in the alive bit set that
//     follows the counters: the C++ side reads it all back at once.
//   - record i: kept, packed to the front of the other record buffer, when its item stays alive (in no particular
//     order: every pass is order-independent — atomic min, max and or). The next iteration runs on these only: a
//     record of a pruned item would still cost its lane's whole warp.
// Both halves decide an item's fate from its flags alone: every record in the list belongs to an item alive before
// this pass (the records of items pruned earlier were dropped then), so no invocation reads what another writes.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_FLAGS) readonly buffer Flags { uint flags[]; };
layout(std430, binding = CULLIDE_SSBO_ALIVE) buffer Alive { uint alive[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_OWNER) readonly buffer Owners { uint owners[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_BOUNDS) readonly buffer Bounds { uint bounds[]; };
layout(std430, binding = CULLIDE_SSBO_COUNTERS) coherent buffer Counters { uint counters[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS) readonly buffer Prims { uvec4 prims[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS_OUT) writeonly buffer PrimsOut { uvec4 primsOut[]; };
layout(location = CULLIDE_LOC_ITEM_COUNT) uniform uint u_itemCount;
layout(location = CULLIDE_LOC_REQUIRED) uniform uint u_required;

// Per work group first (shared-memory atomics), then one global atomic per counter and group. The three axes are
// written out: NVIDIA's GLSL compiler (driver 580.159) crashes the process linking this program when they are a
// loop over shared and global counters indexed by the loop variable (found on an H100; docs/benchmarks.md).
shared uint s_counters[CULLIDE_COUNTER_COUNT];
shared uint s_count;
shared uint s_first;

// Whether an item alive before this pass stays alive.
bool staysAlive(uint item) {
    bool hidden = (flags[item] & u_required) == u_required;
    bool prunes = counters[CULLIDE_COUNTER_OVERFLOWS] == 0u && counters[CULLIDE_DISPATCH_SHORT] == 0u;
    return hidden || !prunes;
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
        } else {
            atomicAdd(s_counters[CULLIDE_COUNTER_ALIVE], 1u);
            atomicOr(counters[CULLIDE_ALIVE_BITS + i / 32u], 1u << (i % 32u));
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
}
