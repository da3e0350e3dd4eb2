// The boxes of the groups of the meshes that move or deform (GpuGeometry::builtRanges, plugin/src/PruningBackend.h),
// built on the device from the positions of the upload, the mapped meshes' included (map.comp runs first): box
// u_first + i is the box of the vertices of the triangles ordered[ranges[2i] .. ranges[2i] + ranges[2i + 1]), grown by
// u_inflate on each side. allBoxes (plugin/src/ClusterGeometry.cpp) computes the same on the CPU, bit for bit: the
// vertices are visited in the same order, each replaces a bound only where it is strictly beyond it (the first of
// equal values stays, -0 and +0 too), and the growth is one float operation per bound (precise). Only the positions
// of these meshes and a transform are sent while they move; their boxes are not. One invocation per box.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_POSITIONS) readonly buffer Positions { float positions[]; };
layout(std430, binding = CULLIDE_SSBO_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, binding = CULLIDE_SSBO_ORDERED) readonly buffer Ordered { uint ordered[]; };
layout(std430, binding = CULLIDE_SSBO_BOX_RANGES) readonly buffer Ranges { uint ranges[]; };
layout(std430, binding = CULLIDE_SSBO_BOXES) writeonly buffer Boxes { float boxes[]; };
layout(location = CULLIDE_LOC_BOX_BASE) uniform uint u_base;
layout(location = CULLIDE_LOC_BOX_FIRST) uniform uint u_first;
layout(location = CULLIDE_LOC_BOX_COUNT) uniform uint u_count;
layout(location = CULLIDE_LOC_BOX_INFLATE) uniform float u_inflate;

vec3 vertexAt(uint i) { return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]); }

void main() {
    uint box = u_base + gl_GlobalInvocationID.x;
    if (box >= u_count) return;
    uint first = ranges[2u * box];
    uint count = ranges[2u * box + 1u];  // at least 1 (a group of k triangles, Settings::groupSize <= 4096)
    // The bounds as bits, chosen by comparisons: no compiler can form a float min or max of them (which of -0 and
    // +0 one returns is not specified), so the boxes are the CPU's (allBoxes) bit for bit.
    uvec3 lo = floatBitsToUint(vertexAt(indices[3u * ordered[first]]));
    uvec3 hi = lo;
    for (uint k = 0u; k < count; ++k) {
        uint t = 3u * ordered[first + k];
        for (uint c = 0u; c < 3u; ++c) {
            vec3 p = vertexAt(indices[t + c]);
            uvec3 bits = floatBitsToUint(p);
            vec3 l = uintBitsToFloat(lo);
            vec3 u = uintBitsToFloat(hi);
            if (p.x < l.x) lo.x = bits.x;
            if (p.y < l.y) lo.y = bits.y;
            if (p.z < l.z) lo.z = bits.z;
            if (p.x > u.x) hi.x = bits.x;
            if (p.y > u.y) hi.y = bits.y;
            if (p.z > u.z) hi.z = bits.z;
        }
    }
    precise vec3 grownLo = uintBitsToFloat(lo) - vec3(u_inflate);
    precise vec3 grownHi = uintBitsToFloat(hi) + vec3(u_inflate);
    uint b = 6u * (u_first + box);
    boxes[b] = grownLo.x;
    boxes[b + 1u] = grownLo.y;
    boxes[b + 2u] = grownLo.z;
    boxes[b + 3u] = grownHi.x;
    boxes[b + 4u] = grownHi.y;
    boxes[b + 5u] = grownHi.z;
}
