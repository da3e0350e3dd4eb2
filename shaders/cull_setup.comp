// Raster back-end, setup: one invocation per (primitive, view axis) computes the primitive's record once per
// iteration, on every core, instead of in the single-threaded vertex stage of each of the three passes.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

void main() {
    uint index = u_primBase + gl_GlobalInvocationID.x;
    if (index >= u_primCount) return;
    int axis = int(gl_GlobalInvocationID.y);
    records[uint(axis) * u_primCount + index] = toRecord(makePrim(index, axis));
}
