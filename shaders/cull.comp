// Compute back-end: one invocation per (primitive band, view axis) scans its share of the primitive's conservative
// footprint (every `bands`-th pixel, starting at `band`) and runs the same coverage test and per-pixel bookkeeping as
// the fragment stage. On llvmpipe this runs on every core (the raster back-end's vertex stage is single-threaded);
// on a GPU it avoids the fixed-function path. Dispatched indirectly (CULLIDE_DISPATCH_CULL): work groups along x and
// z, the view along y.

layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_COUNTERS) coherent buffer Counters { uint counters[]; };

void main() {
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                 gl_LocalInvocationID.x;
    if (index >= counters[CULLIDE_DISPATCH_RECORDS]) return;
    int axis = int(gl_GlobalInvocationID.y);
    if (!axisEnabled(axis) || !primAlive(index)) return;
    uint band = prims[index].z;
    uint bands = prims[index].w;
    Prim p = makePrim(index, axis);
    vec2 h = halfSizeFor(axis);
    // Pixel centres i + 0.5 whose square may touch the rectangle.
    ivec2 first = max(ivec2(floor(p.rect.xy - h - vec2(0.5))), ivec2(0));
    ivec2 last = min(ivec2(ceil(p.rect.zw + h - vec2(0.5))), ivec2(u_resolution - 1));
    if (last.x < first.x || last.y < first.y) return;
    uint width = uint(last.x - first.x + 1);
    uint total = width * uint(last.y - first.y + 1);
    if (band >= total) return;
    if ((total - band + bands - 1u) / bands > uint(CULLIDE_MAX_LOOP_ITERATIONS)) {
        atomicAdd(counters[CULLIDE_COUNTER_OVERFLOWS], 1u);
        return;
    }
    uint bits = 0u;
    for (uint k = band; k < total; k += bands) {
        int x = first.x + int(k % width);
        int y = first.y + int(k / width);
        vec2 c = vec2(float(x) + 0.5, float(y) + 0.5);
        float zlo;
        float zhi;
        if (!coverage(p, c, h, zlo, zhi)) continue;
        bits |= visit(ivec2(x + axis * u_resolution, y), p.owner, axis, zlo, zhi);
    }
    setFlags(p.item, bits);
}
