// Raster back-end, setup: one invocation per (primitive, view axis) computes the primitive's record once per
// iteration, on every core, instead of in the single-threaded vertex stage of each of the three passes. Dispatched
// indirectly (CULLIDE_DISPATCH_CULL): work groups along x and z, the view along y.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

void main() {
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                 gl_LocalInvocationID.x;
    uint count = recordCount();
    if (index >= count) return;
    int axis = int(gl_GlobalInvocationID.y);
    records[uint(axis) * count + index] = toRecord(makePrim(index, axis));
}
