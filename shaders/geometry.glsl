// The upload's geometry as the record build (build.comp), a level's start (start.comp) and the exact stage
// (exact.comp) read it: the positions, the triangles' indices and the boxes, a triangle's vertices, a primitive's box,
// a box test against a grown box, and the float bits the items' bounds are gathered in.
layout(std430, binding = CULLIDE_SSBO_POSITIONS) readonly buffer Positions { float positions[]; };
layout(std430, binding = CULLIDE_SSBO_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, binding = CULLIDE_SSBO_BOXES) readonly buffer Boxes { float boxes[]; };

vec3 vertexAt(uint i) { return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]); }

// The vertices of triangle t.
void triangleAt(uint t, out vec3 a, out vec3 b, out vec3 c) {
    a = vertexAt(indices[3u * t]);
    b = vertexAt(indices[3u * t + 1u]);
    c = vertexAt(indices[3u * t + 2u]);
}

// The box of a primitive: a box of the upload, or a triangle of its positions.
void primBox(uint ref, out vec3 lo, out vec3 hi) {
    if ((ref & CULLIDE_PRIM_BOX_BIT) != 0u) {
        uint b = (ref & ~CULLIDE_PRIM_BOX_BIT) * 6u;
        lo = vec3(boxes[b], boxes[b + 1u], boxes[b + 2u]);
        hi = vec3(boxes[b + 3u], boxes[b + 4u], boxes[b + 5u]);
        return;
    }
    vec3 a, b, c;
    triangleAt(ref, a, b, c);
    lo = min(min(a, b), c);
    hi = max(max(a, b), c);
}

// Whether (lo, hi) meets box b of the upload grown by `slack` on each side (closed intervals).
bool meetsGrownBox(vec3 lo, vec3 hi, uint b, float slack) {
    uint at = 6u * b;
    precise vec3 bLo = vec3(boxes[at], boxes[at + 1u], boxes[at + 2u]) - vec3(slack);
    precise vec3 bHi = vec3(boxes[at + 3u], boxes[at + 4u], boxes[at + 5u]) + vec3(slack);
    return all(lessThanEqual(lo, bHi)) && all(lessThanEqual(bLo, hi));
}

// Float bits whose unsigned order is the floats' order (for atomicMin / atomicMax; gather.glsl reads them back).
uint orderedBits(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
