// CULLIDE visibility pass, fragment stage. Per pixel (of one of the three side-by-side views) it keeps the
// nearest and farthest packed depth with its owner, the same among the other owners, and flags items that are
// not fully visible w.r.t. the items of every other object, from either side. In reliable mode every pixel whose
// square (dilated by the margin) touches the primitive is covered and the depth is the primitive's range over it.

layout(std430, binding = CULLIDE_SSBO_FLAGS) coherent buffer Flags { uint flags[]; };
layout(binding = CULLIDE_IMAGE_NEAR1, r32ui) coherent uniform uimage2D u_near1;
layout(binding = CULLIDE_IMAGE_FAR1, r32ui) coherent uniform uimage2D u_far1;
layout(binding = CULLIDE_IMAGE_NEAR2, r32ui) coherent uniform uimage2D u_near2;
layout(binding = CULLIDE_IMAGE_FAR2, r32ui) coherent uniform uimage2D u_far2;

layout(location = CULLIDE_LOC_PASS) uniform int u_pass;
layout(location = CULLIDE_LOC_RESOLUTION) uniform int u_resolution;
layout(location = CULLIDE_LOC_HALF_SIZE) uniform vec3 u_halfSize;
layout(location = CULLIDE_LOC_DEPTH_PAD) uniform vec3 u_depthPad;
layout(location = CULLIDE_LOC_ID_BITS) uniform uint u_idBits;
layout(location = CULLIDE_LOC_CONSERVATIVE) uniform int u_conservative;

flat in vec4 v_rect;
flat in vec3 v_edge[3];
flat in vec4 v_plane;
flat in vec2 v_origin;
flat in vec2 v_zrange;
flat in uint v_item;
flat in uint v_owner;
flat in int v_axis;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec2 c = gl_FragCoord.xy - vec2(float(v_axis * u_resolution), 0.0);
    if (c.x < 0.0 || c.x >= float(u_resolution)) discard;  // belongs to a neighbouring view
    int ua = (v_axis + 1) % 3;
    int va = (v_axis + 2) % 3;
    vec2 h = u_conservative != 0 ? vec2(u_halfSize[ua], u_halfSize[va]) : vec2(0.0);

    // Pixel square [c - h, c + h] against the rectangle and the three edge half-planes (separating axes).
    if (c.x + h.x < v_rect.x || c.x - h.x > v_rect.z || c.y + h.y < v_rect.y || c.y - h.y > v_rect.w) discard;
    for (int i = 0; i < 3; ++i) {
        vec3 e = v_edge[i];
        if (e.x * c.x + e.y * c.y + e.z - (h.x * abs(e.x) + h.y * abs(e.y)) > 0.0) discard;
    }

    // Depth range of the primitive over the square.
    float zlo = v_zrange.x;
    float zhi = v_zrange.y;
    if (v_plane.w != 0.0) {
        float zc = v_plane.z + v_plane.x * (c.x - v_origin.x) + v_plane.y * (c.y - v_origin.y);
        float r = h.x * abs(v_plane.x) + h.y * abs(v_plane.y);
        float lo = max(zc - r, zlo);
        float hi = min(zc + r, zhi);
        if (lo <= hi) {
            zlo = lo;
            zhi = hi;
        } else if (u_conservative == 0) {
            zlo = clamp(zc, v_zrange.x, v_zrange.y);
            zhi = zlo;
        }
    }
    if (u_conservative != 0) {
        float pad = u_depthPad[v_axis] + (v_zrange.y - v_zrange.x) * (1.0 / 4096.0);
        zlo -= pad;
        zhi += pad;
    }

    // Quantize conservatively: near depths round down, far depths round up. maxQ leaves the all-ones value free
    // as the "empty" marker of the near images; far depths are stored + 1 so that 0 marks "empty".
    uint depthBits = min(24u, 32u - u_idBits);  // a float holds 24 bits exactly
    float maxQ = float((1u << depthBits) - 2u);
    uint qlo = uint(floor(clamp(zlo, 0.0, 1.0) * maxQ));
    uint qhi = uint(ceil(clamp(zhi, 0.0, 1.0) * maxQ));
    uint idMask = (1u << u_idBits) - 1u;
    uint nearPacked = (qlo << u_idBits) | v_owner;
    uint farPacked = ((qhi + 1u) << u_idBits) | v_owner;

    if (u_pass == CULLIDE_PASS_NEAREST) {
        imageAtomicMin(u_near1, pixel, nearPacked);
        imageAtomicMax(u_far1, pixel, farPacked);
    } else if (u_pass == CULLIDE_PASS_SECOND) {
        uint n1 = imageLoad(u_near1, pixel).x;
        if ((n1 & idMask) != v_owner) imageAtomicMin(u_near2, pixel, nearPacked);
        uint f1 = imageLoad(u_far1, pixel).x;
        if ((f1 & idMask) != v_owner) imageAtomicMax(u_far2, pixel, farPacked);
    } else {
        uint n1 = imageLoad(u_near1, pixel).x;
        uint nearOther = (n1 & idMask) == v_owner ? imageLoad(u_near2, pixel).x : n1;
        uint f1 = imageLoad(u_far1, pixel).x;
        uint farOther = (f1 & idMask) == v_owner ? imageLoad(u_far2, pixel).x : f1;
        uint bits = 0u;
        // Seen from the near side, the item is hidden somewhere by another object: its far depth reaches the
        // nearest depth of another object at this pixel.
        if (nearOther != 0xFFFFFFFFu && qhi >= (nearOther >> u_idBits)) bits |= 1u << uint(2 * v_axis);
        if (farOther != 0u && qlo + 1u <= (farOther >> u_idBits)) bits |= 1u << uint(2 * v_axis + 1);
        if (bits != 0u && (flags[v_item] & bits) != bits) atomicOr(flags[v_item], bits);
    }
}
