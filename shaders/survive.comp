// Raster back-end: after an iteration's flag pass (a draw, whose fragments cannot tell when an item's flags are all
// in), one dispatch over max(items, records) invocations (CULLIDE_DISPATCH_SURVIVE):
//   - item i: alive at the iteration's start, decided (iteration.glsl's decideItem).
//   - record i: kept, packed to the front of the other record buffer (pack.glsl), when its item stays alive. The next
//     iteration runs on these only.
// Both halves decide an item's fate from its flags alone: every record in the list belongs to an item alive before
// this pass (the records of items pruned earlier were dropped then), so no invocation reads what another writes.
// The last work group to finish ends the iteration (iteration.glsl's finishIteration).
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

void main() {
    uint lane = gl_LocalInvocationID.x;
    clearGroupCounters();
    barrier();
    uint i = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + lane;
    if (i < u_itemCount && alive[i] != 0u) decideItem(i);
    keepRecord(i, i < counters[CULLIDE_DISPATCH_RECORDS] && staysAlive(prims[i].y));  // its barriers order the above
    if (lane == 0u) addGroupCounters();
    if (!lastGroupToFinish() || lane != 0u) return;
    uint kept = counters[CULLIDE_COUNTER_RECORDS];
    finishIteration(counters[CULLIDE_DISPATCH_RECORDS], kept, max(kept, u_itemCount));
}
