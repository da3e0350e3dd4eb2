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
    precise vec3 lo = vertexAt(indices[3u * ordered[first]]);  // precise: no compare-and-select made a min or max
    precise vec3 hi = lo;
    for (uint k = 0u; k < count; ++k) {
        uint t = 3u * ordered[first + k];
        for (uint c = 0u; c < 3u; ++c) {
            vec3 p = vertexAt(indices[t + c]);
            // Written out per component (no min/max: which of -0 and +0 they return is not specified).
            if (p.x < lo.x) lo.x = p.x;
            if (p.y < lo.y) lo.y = p.y;
            if (p.z < lo.z) lo.z = p.z;
            if (p.x > hi.x) hi.x = p.x;
            if (p.y > hi.y) hi.y = p.y;
            if (p.z > hi.z) hi.z = p.z;
        }
    }
    precise vec3 grownLo = lo - vec3(u_inflate);
    precise vec3 grownHi = hi + vec3(u_inflate);
    uint b = 6u * (u_first + box);
    boxes[b] = grownLo.x;
    boxes[b + 1u] = grownLo.y;
    boxes[b + 2u] = grownLo.z;
    boxes[b + 3u] = grownHi.x;
    boxes[b + 4u] = grownHi.y;
    boxes[b + 5u] = grownHi.z;
}
