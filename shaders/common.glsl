// Shared by every CULLIDE visibility shader: resources, the per-primitive setup, the conservative pixel test and
// the per-pixel depth bookkeeping. Both back-ends (raster: cull.vert/cull.frag; compute: cull.comp) run exactly
// this code, so they give the same answer. Every value the test depends on is `precise`: no fused multiply-add, no
// reassociation, on any driver. The CPU reference (plugin/src/ReferenceVisibility.cpp) performs the same float
// operations in the same order, and the GL tests require the same answers, iteration by iteration.

layout(std430, binding = CULLIDE_SSBO_POSITIONS) readonly buffer Positions { float positions[]; };
layout(std430, binding = CULLIDE_SSBO_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, binding = CULLIDE_SSBO_BOXES) readonly buffer Boxes { float boxes[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS) readonly buffer Prims { uvec4 prims[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_OWNER) readonly buffer Owners { uint owners[]; };
layout(std430, binding = CULLIDE_SSBO_ALIVE) buffer Alive { uint alive[]; };  // written where an iteration ends

layout(location = CULLIDE_LOC_PASS) uniform int u_pass;
layout(location = CULLIDE_LOC_RESOLUTION) uniform int u_resolution;
layout(location = CULLIDE_LOC_CONSERVATIVE) uniform int u_conservative;
layout(location = CULLIDE_LOC_AXES) uniform uint u_axes;

// Items pruned by an earlier iteration of the level are neither drawn nor occluders.
bool primAlive(uint index) { return alive[prims[index].y] != 0u; }

bool axisEnabled(int axis) { return ((u_axes >> uint(axis)) & 1u) != 0u; }

// std430 layout of a primitive record written by cull_setup.comp: 24 floats (vec4-aligned members only).
struct PrimRecord {
    vec4 rect;
    vec4 edge0;   // xyz used
    vec4 edge1;
    vec4 edge2;
    vec4 plane;
    vec4 originZrange;  // (x0, y0, zmin, zmax)
    uvec4 ids;          // (item, owner, axis, 0)
};

struct Prim {
    vec4 rect;     // 2D bounding rectangle (pixels, undilated)
    vec3 edge0;    // edge functions (nx, ny, c): inside <= 0; (0, 0, -1) disables an edge
    vec3 edge1;
    vec3 edge2;
    vec4 plane;    // depth plane z = z0 + a*(x - x0) + b*(y - y0): (a, b, z0, valid)
    vec2 origin;   // (x0, y0)
    vec2 zrange;   // the primitive's own depth range
    uint item;
    uint owner;
    int axis;
};

vec3 vertexAt(uint i) { return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]); }

// World point -> (pixel x, pixel y, normalized depth) for the view along `axis`.
vec3 project(vec3 p, int axis) {
    int ua = (axis + 1) % 3;
    int va = (axis + 2) % 3;
    ViewRecord v = views[u_iteration];
    precise vec3 r = vec3((p[ua] - v.lo[ua]) * v.pixelScale[ua], (p[va] - v.lo[va]) * v.pixelScale[va],
                          (p[axis] - v.lo[axis]) * v.depthScale[axis]);
    return r;
}

vec3 edgeFunction(vec2 from, vec2 to, float s) {
    precise vec2 e = to - from;
    precise vec2 n = s * vec2(e.y, -e.x);
    precise float c = -(n.x * from.x + n.y * from.y);
    return vec3(n, c);
}

// 1 / x rounded to the nearest float, as the CPU's division rounds it: GLSL allows "/" 2.5 ulp (a driver may divide
// through an approximate reciprocal), so the quotient is moved to the nearest float by exact residuals. For a float c within a few ulp
// of 1 / x, c * x is exact in double (48 bits) and so is 1 - c * x (Sterbenz): |1 - c x| / |x| is c's distance from
// 1 / x. This assumes IEEE double multiplication and subtraction (GLSL promises only single precision for double
// operations; every GL 4.5 device with native fp64 is IEEE). x is finite and not near 0 here (|x| > 1e-3). A quotient
// 2.5 ulp off near a power of two may be 5 steps of the finer spacing away: 8 steps are allowed, one is usual.
float nearestReciprocal(float x) {
    precise float q = 1.0 / x;
    for (int k = 0; k < 8; ++k) {
        float smaller = uintBitsToFloat(floatBitsToUint(q) - 1u);  // one ulp towards 0
        float larger = uintBitsToFloat(floatBitsToUint(q) + 1u);   // one ulp away from 0
        precise double e = abs(1.0lf - double(q) * double(x));
        precise double eSmaller = abs(1.0lf - double(smaller) * double(x));
        precise double eLarger = abs(1.0lf - double(larger) * double(x));
        if (eSmaller < e) {
            q = smaller;
        } else if (eLarger < e) {
            q = larger;
        } else {
            break;
        }
    }
    return q;
}

Prim makePrim(uint index, int axis) {
    Prim p;
    uvec4 entry = prims[index];
    p.item = entry.y;
    p.owner = owners[entry.y];
    p.axis = axis;
    p.edge0 = vec3(0.0, 0.0, -1.0);
    p.edge1 = vec3(0.0, 0.0, -1.0);
    p.edge2 = vec3(0.0, 0.0, -1.0);
    p.plane = vec4(0.0);
    p.origin = vec2(0.0);
    if ((entry.x & CULLIDE_PRIM_BOX_BIT) != 0u) {
        uint b = (entry.x & ~CULLIDE_PRIM_BOX_BIT) * 6u;
        vec3 lo = project(vec3(boxes[b], boxes[b + 1u], boxes[b + 2u]), axis);
        vec3 hi = project(vec3(boxes[b + 3u], boxes[b + 4u], boxes[b + 5u]), axis);
        p.rect = vec4(lo.xy, hi.xy);
        p.zrange = vec2(lo.z, hi.z);
        return p;
    }
    uint t = entry.x * 3u;
    vec3 p0 = project(vertexAt(indices[t]), axis);
    vec3 p1 = project(vertexAt(indices[t + 1u]), axis);
    vec3 p2 = project(vertexAt(indices[t + 2u]), axis);
    p.rect = vec4(min(min(p0.xy, p1.xy), p2.xy), max(max(p0.xy, p1.xy), p2.xy));
    p.zrange = vec2(min(min(p0.z, p1.z), p2.z), max(max(p0.z, p1.z), p2.z));
    precise vec2 d1 = p1.xy - p0.xy;
    precise vec2 d2 = p2.xy - p0.xy;
    precise vec2 d3 = p2.xy - p1.xy;
    precise float area2 = d1.x * d2.y - d1.y * d2.x;
    precise float maxEdge2 = max(max(d1.x * d1.x + d1.y * d1.y, d2.x * d2.x + d2.y * d2.y), d3.x * d3.x + d3.y * d3.y);
    // Well-conditioned in 2D: exact edge tests and a depth plane. Otherwise (edge-on, needle-like or tiny in
    // projection) the rectangle and the triangle's own depth range are used: coarser, still conservative.
    if (abs(area2) > 1.0e-3 && abs(area2) >= maxEdge2 * (1.0 / 256.0)) {
        float s = area2 > 0.0 ? 1.0 : -1.0;
        p.edge0 = edgeFunction(p0.xy, p1.xy, s);
        p.edge1 = edgeFunction(p1.xy, p2.xy, s);
        p.edge2 = edgeFunction(p2.xy, p0.xy, s);
        precise float invArea = nearestReciprocal(area2);
        precise float pa = ((p1.z - p0.z) * d2.y - (p2.z - p0.z) * d1.y) * invArea;
        precise float pb = ((p2.z - p0.z) * d1.x - (p1.z - p0.z) * d2.x) * invArea;
        p.plane = vec4(pa, pb, p0.z, 1.0);
        p.origin = p0.xy;
    }
    return p;
}

// Half size of the tested square in pixels along the view's two image axes (0 in sampled mode: the centre only).
vec2 halfSizeFor(int axis) {
    return u_conservative != 0 ? vec2(views[u_iteration].halfSize[(axis + 1) % 3],
                                      views[u_iteration].halfSize[(axis + 2) % 3])
                               : vec2(0.0);
}

bool edgeRejects(vec3 e, vec2 c, vec2 h) {
    precise float v = e.x * c.x + e.y * c.y + e.z - (h.x * abs(e.x) + h.y * abs(e.y));
    return v > 0.0;
}

// Pixel square [c - h, c + h] against the rectangle and the three edge half-planes (separating axes); on success
// the primitive's depth range over the square (padded in reliable mode).
bool coverage(Prim p, vec2 c, vec2 h, out precise float zlo, out precise float zhi) {
    zlo = 0.0;
    zhi = 0.0;
    if (c.x + h.x < p.rect.x || c.x - h.x > p.rect.z || c.y + h.y < p.rect.y || c.y - h.y > p.rect.w) return false;
    if (edgeRejects(p.edge0, c, h) || edgeRejects(p.edge1, c, h) || edgeRejects(p.edge2, c, h)) return false;
    zlo = p.zrange.x;
    zhi = p.zrange.y;
    if (p.plane.w != 0.0) {
        precise float zc = p.plane.z + p.plane.x * (c.x - p.origin.x) + p.plane.y * (c.y - p.origin.y);
        precise float r = h.x * abs(p.plane.x) + h.y * abs(p.plane.y);
        precise float lo = max(zc - r, zlo);
        precise float hi = min(zc + r, zhi);
        if (lo <= hi) {
            zlo = lo;
            zhi = hi;
        } else if (u_conservative == 0) {
            zlo = clamp(zc, p.zrange.x, p.zrange.y);
            zhi = zlo;
        }
    }
    if (u_conservative != 0) {
        precise float pad = views[u_iteration].depthPad[p.axis] + (p.zrange.y - p.zrange.x) * (1.0 / 4096.0);
        zlo -= pad;
        zhi += pad;
    }
    return true;
}
