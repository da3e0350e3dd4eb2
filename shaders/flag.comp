// Compute back-end, the flag pass (cull.comp has the two before it): each invocation scans its share of a record's
// footprint (scan.glsl) over the records the nearest pass packed, sets its item's flags and counts itself done for
// the item (CULLIDE_SSBO_ITEM_BOUNDS: the item's records, from the build, times the enabled views). The item's last
// invocation, which sees all of its flags, decides its fate; the last work group ends the iteration (iteration.glsl):
// no survivor pass. Dispatched indirectly as the nearest pass (CULLIDE_DISPATCH_CULL).

layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

// Whether this is the last of the flag pass's invocations over `item` (its records times the enabled views): all of
// its flags are in (the counts start at 0 in every iteration: the C++ side clears them).
bool lastForItem(uint item) {
    memoryBarrierBuffer();
    uint expected = bounds[6u * u_itemCount + item] * uint(bitCount(u_axes & 7u));
    if (atomicAdd(bounds[7u * u_itemCount + item], 1u) + 1u != expected) return false;
    memoryBarrierBuffer();
    return true;
}

void main() {
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                 gl_LocalInvocationID.x;
    int axis = int(gl_GlobalInvocationID.y);
    uint records = counters[CULLIDE_COUNTER_RECORDS];
    bool counted = index < records && primAlive(index) && axisEnabled(axis);
    uint item = counted ? prims[index].y : 0u;
    if (counted) setFlags(item, scan(index, axis));
    clearGroupCounters();
    barrier();
    if (counted && lastForItem(item)) decideItem(item);
    barrier();
    if (gl_LocalInvocationID.x == 0u) addGroupCounters();
    if (!lastGroupToFinish() || gl_LocalInvocationID.x != 0u) return;
    finishIteration(records, records, 0u);
}
