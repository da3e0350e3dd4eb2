// Raster back-end: after an iteration's flag pass (a draw, whose fragments cannot tell when an item's flags are all
// in), one dispatch over max(items, records) invocations (CULLIDE_DISPATCH_SURVIVE):
//   - item i: alive at the iteration's start, decided (iteration.glsl's decideItem).
//   - record i: kept, packed to the front of the other record buffer, when its item stays alive (in no particular
//     order: every pass is order-independent — atomic min, max and or). The next iteration runs on these only.
// Both halves decide an item's fate from its flags alone: every record in the list belongs to an item alive before
// this pass (the records of items pruned earlier were dropped then), so no invocation reads what another writes.
// The last work group to finish ends the iteration (iteration.glsl's finishIteration).
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_PRIMS_OUT) writeonly buffer PrimsOut { uvec4 primsOut[]; };

shared uint s_count;
shared uint s_first;

void main() {
    uint lane = gl_LocalInvocationID.x;
    clearGroupCounters();
    if (lane == 0u) s_count = 0u;
    barrier();
    uint i = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + lane;
    if (i < u_itemCount && alive[i] != 0u) decideItem(i);
    uvec4 record = uvec4(0u);
    bool keep = false;
    if (i < counters[CULLIDE_DISPATCH_RECORDS]) {
        record = prims[i];
        keep = staysAlive(record.y);
    }
    uint slot = keep ? atomicAdd(s_count, 1u) : 0u;
    barrier();
    if (lane == 0u && s_count != 0u) s_first = atomicAdd(counters[CULLIDE_COUNTER_RECORDS], s_count);
    if (lane == 0u) addGroupCounters();
    barrier();
    if (keep) primsOut[s_first + slot] = record;
    if (!lastGroupToFinish() || lane != 0u) return;
    uint kept = counters[CULLIDE_COUNTER_RECORDS];
    finishIteration(counters[CULLIDE_DISPATCH_RECORDS], kept, max(kept, u_itemCount));
}
