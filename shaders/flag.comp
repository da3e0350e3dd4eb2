// Compute back-end, the flag pass (cull.comp has the two before it): each invocation scans its share of a record's
// footprint (scan.glsl) over the records the nearest pass packed, sets its item's flags and counts itself done for
// the item (CULLIDE_SSBO_ITEM_BOUNDS: the item's records, from the build, times the enabled views). The item's last
// invocation, which sees all of its flags, decides its fate; the last work group ends the iteration (iteration.glsl):
// no survivor pass. Dispatched indirectly as the nearest pass (CULLIDE_DISPATCH_CULL).

layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

const uint kNoItem = 0xFFFFFFFFu;
shared uint s_item[CULLIDE_COMPUTE_GROUP_SIZE];  // per lane: the item it counted for, or kNoItem

// Whether this lane heads its work group's run of lanes over `item` and the run completes the item's count (its
// records times the enabled views): all of its flags are in. One atomic add per run, not per lane: an item's records
// lie together, and a whole-mesh item (the paper's pipeline) has thousands. The counts start at 0 in every iteration
// (the C++ side clears them). Every lane calls it.
bool completesItem(bool counted, uint item) {
    uint lane = gl_LocalInvocationID.x;
    memoryBarrierBuffer();  // this lane's flags before the run's count
    s_item[lane] = counted ? item : kNoItem;
    barrier();
    if (!counted || (lane > 0u && s_item[lane - 1u] == item)) return false;
    uint run = 1u;
    while (lane + run < gl_WorkGroupSize.x && s_item[lane + run] == item) ++run;
    uint expected = bounds[6u * u_itemCount + item] * uint(bitCount(u_axes & 7u));
    if (atomicAdd(bounds[7u * u_itemCount + item], run) + run != expected) return false;
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
    clearGroupCounters();  // before completesItem's barrier
    if (completesItem(counted, item)) decideItem(item);
    barrier();
    if (gl_LocalInvocationID.x == 0u) addGroupCounters();
    if (!lastGroupToFinish() || gl_LocalInvocationID.x != 0u) return;
    finishIteration(records, records, 0u);
}
