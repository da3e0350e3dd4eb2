// After the survivor pass: the records of the items still alive, packed to the front of the other record buffer
// (in no particular order: every pass is order-independent — atomic min, max and or). The next iteration runs on
// these only: a record of a pruned item would still cost its lane's whole warp. Dispatched indirectly
// (CULLIDE_DISPATCH_COMPACT): work groups along x and z.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_PRIMS) readonly buffer Prims { uvec4 prims[]; };
layout(std430, binding = CULLIDE_SSBO_ALIVE) readonly buffer Alive { uint alive[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS_OUT) writeonly buffer PrimsOut { uvec4 primsOut[]; };
layout(std430, binding = CULLIDE_SSBO_COUNTERS) coherent buffer Counters { uint counters[]; };

shared uint s_count;
shared uint s_first;

void main() {
    uint lane = gl_LocalInvocationID.x;
    if (lane == 0u) s_count = 0u;
    barrier();
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + lane;
    uvec4 record = uvec4(0u);
    bool keep = false;
    if (index < counters[CULLIDE_DISPATCH_RECORDS]) {
        record = prims[index];
        keep = alive[record.y] != 0u;
    }
    uint slot = keep ? atomicAdd(s_count, 1u) : 0u;
    barrier();
    if (lane == 0u && s_count != 0u) s_first = atomicAdd(counters[CULLIDE_COUNTER_RECORDS], s_count);
    barrier();
    if (keep) primsOut[s_first + slot] = record;
}
