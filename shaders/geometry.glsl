// The upload's geometry as the record build (build.comp) and a level's start (start.comp) read it: the positions,
// the triangles' indices and the boxes, a primitive's box, and the float bits the items' bounds are gathered in.
layout(std430, binding = CULLIDE_SSBO_POSITIONS) readonly buffer Positions { float positions[]; };
layout(std430, binding = CULLIDE_SSBO_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, binding = CULLIDE_SSBO_BOXES) readonly buffer Boxes { float boxes[]; };

vec3 vertexAt(uint i) { return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]); }

// The box of a primitive: a box of the upload, or a triangle of its positions.
void primBox(uint ref, out vec3 lo, out vec3 hi) {
    if ((ref & CULLIDE_PRIM_BOX_BIT) != 0u) {
        uint b = (ref & ~CULLIDE_PRIM_BOX_BIT) * 6u;
        lo = vec3(boxes[b], boxes[b + 1u], boxes[b + 2u]);
        hi = vec3(boxes[b + 3u], boxes[b + 4u], boxes[b + 5u]);
        return;
    }
    uint t = ref * 3u;
    vec3 a = vertexAt(indices[t]);
    vec3 b = vertexAt(indices[t + 1u]);
    vec3 c = vertexAt(indices[t + 2u]);
    lo = min(min(a, b), c);
    hi = max(max(a, b), c);
}

// Float bits whose unsigned order is the floats' order (for atomicMin / atomicMax; gather.glsl reads them back).
uint orderedBits(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
