// Per-pixel depth bookkeeping, shared by the fragment and compute back-ends. Needs the image and flag bindings.

layout(std430, binding = CULLIDE_SSBO_FLAGS) coherent buffer Flags { uint flags[]; };
layout(binding = CULLIDE_IMAGE_NEAR1, r32ui) coherent uniform uimage2D u_near1;
layout(binding = CULLIDE_IMAGE_FAR1, r32ui) coherent uniform uimage2D u_far1;
layout(binding = CULLIDE_IMAGE_NEAR2, r32ui) coherent uniform uimage2D u_near2;
layout(binding = CULLIDE_IMAGE_FAR2, r32ui) coherent uniform uimage2D u_far2;

// Quantize conservatively: near depths round down, far depths round up. maxQ leaves the all-ones value free as the
// "empty" marker of the near images; far depths are stored + 1 so that 0 marks "empty". At most 24 depth bits:
// a float holds the scale exactly.
uint quantizeDown(float z, float maxQ) {
    precise float q = clamp(z, 0.0, 1.0) * maxQ;
    return uint(floor(q));
}
uint quantizeUp(float z, float maxQ) {
    precise float q = clamp(z, 0.0, 1.0) * maxQ;
    return uint(ceil(q));
}

// Returns the flag bits this pixel earns the item in the flag pass (0 in the other passes).
uint visit(ivec2 pixel, uint owner, int axis, float zlo, float zhi) {
    uint idBits = views[u_iteration].idBits;
    uint depthBits = min(24u, 32u - idBits);
    float maxQ = float((1u << depthBits) - 2u);
    uint qlo = quantizeDown(zlo, maxQ);
    uint qhi = quantizeUp(zhi, maxQ);
    uint idMask = (1u << idBits) - 1u;
    if (u_pass == CULLIDE_PASS_NEAREST) {
        imageAtomicMin(u_near1, pixel, (qlo << idBits) | owner);
        imageAtomicMax(u_far1, pixel, ((qhi + 1u) << idBits) | owner);
        return 0u;
    }
    uint n1 = imageLoad(u_near1, pixel).x;
    uint f1 = imageLoad(u_far1, pixel).x;
    if (u_pass == CULLIDE_PASS_SECOND) {
        if ((n1 & idMask) != owner) imageAtomicMin(u_near2, pixel, (qlo << idBits) | owner);
        if ((f1 & idMask) != owner) imageAtomicMax(u_far2, pixel, ((qhi + 1u) << idBits) | owner);
        return 0u;
    }
    uint nearOther = (n1 & idMask) == owner ? imageLoad(u_near2, pixel).x : n1;
    uint farOther = (f1 & idMask) == owner ? imageLoad(u_far2, pixel).x : f1;
    uint bits = 0u;
    // Seen from the near side the item is hidden somewhere by another object: its far depth reaches the nearest
    // depth of another object at this pixel. Symmetrically from the far side.
    if (nearOther != 0xFFFFFFFFu && qhi >= (nearOther >> idBits)) bits |= 1u << uint(2 * axis);
    if (farOther != 0u && qlo + 1u <= (farOther >> idBits)) bits |= 1u << uint(2 * axis + 1);
    return bits;
}

void setFlags(uint item, uint bits) {
    if (bits != 0u && (flags[item] & bits) != bits) atomicOr(flags[item], bits);
}
