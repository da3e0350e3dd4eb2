// Compute back-end, the nearest pass: one invocation per (primitive band, view axis) scans its share of the
// primitive's conservative footprint (scan.glsl). On llvmpipe this runs on every core (the raster back-end's vertex
// stage is single-threaded); on a GPU it avoids the fixed-function path. Dispatched indirectly
// (CULLIDE_DISPATCH_CULL): work groups along x and z, the view along y. An iteration is this pass, the second pass
// (second.comp) and the flag pass (flag.comp), with no survivor pass: this one runs over the records the last
// iteration ran over and packs those of the items still alive into the other record buffer
// (CULLIDE_SSBO_PRIMS_OUT; CULLIDE_COUNTER_RECORDS of them), so that the other two run over these only and a pruned
// item's record costs no lane of theirs. They are dispatched over as many work groups as this pass: the ones past
// the packed records do nothing. Each pass is a program of its own: the packing and the flag pass's end need
// work-group barriers, which the second pass's scan does without (llvmpipe runs a program with barriers as
// coroutines).

layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;

void main() {
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                 gl_LocalInvocationID.x;
    int axis = int(gl_GlobalInvocationID.y);
    bool live = index < counters[CULLIDE_DISPATCH_RECORDS] && primAlive(index);
    if (gl_WorkGroupID.y == 0u) keepRecord(index, live);  // pack.glsl: the work groups along the first view
    if (live && axisEnabled(axis)) scan(index, axis);
}
