// Compute back-end, the second pass (cull.comp has the nearest pass, flag.comp the flag pass): each invocation scans
// its share of a record's footprint (scan.glsl) over the records the nearest pass packed (those of the items alive).
// No work-group barrier: a program of its own. Dispatched indirectly as the nearest pass (CULLIDE_DISPATCH_CULL); the
// work groups past the packed records do nothing.

layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

void main() {
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                 gl_LocalInvocationID.x;
    int axis = int(gl_GlobalInvocationID.y);
    if (index < counters[CULLIDE_COUNTER_RECORDS] && axisEnabled(axis)) scan(index, axis);
}
