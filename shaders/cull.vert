// CULLIDE visibility pass, vertex stage. One triangle per primitive; instance = view axis (0, 1, 2).
// Each primitive is drawn as a triangle that covers its (dilated) 2D bounding rectangle; the fragment stage does
// the exact pixel-square test. All three vertices compute the same flat data, so the result is crack-free.

layout(std430, binding = CULLIDE_SSBO_POSITIONS) readonly buffer Positions { float positions[]; };
layout(std430, binding = CULLIDE_SSBO_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, binding = CULLIDE_SSBO_BOXES) readonly buffer Boxes { float boxes[]; };
layout(std430, binding = CULLIDE_SSBO_PRIMS) readonly buffer Prims { uvec2 prims[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_OWNER) readonly buffer Owners { uint owners[]; };

layout(location = CULLIDE_LOC_RESOLUTION) uniform int u_resolution;
layout(location = CULLIDE_LOC_VIEW_LO) uniform vec3 u_viewLo;
layout(location = CULLIDE_LOC_PIXEL_SCALE) uniform vec3 u_pixelScale;
layout(location = CULLIDE_LOC_DEPTH_SCALE) uniform vec3 u_depthScale;
layout(location = CULLIDE_LOC_HALF_SIZE) uniform vec3 u_halfSize;
layout(location = CULLIDE_LOC_CONSERVATIVE) uniform int u_conservative;

flat out vec4 v_rect;     // 2D bounding rectangle of the primitive (pixels, undilated)
flat out vec3 v_edge[3];  // edge functions (nx, ny, c): inside <= 0; (0, 0, -1) disables an edge
flat out vec4 v_plane;    // depth plane z = a*x + b*y + c around (x0, y0) packed as (a, b, c, valid)
flat out vec2 v_origin;   // (x0, y0) of the plane
flat out vec2 v_zrange;   // the primitive's own depth range
flat out uint v_item;
flat out uint v_owner;
flat out int v_axis;

vec3 vertexAt(uint i) { return vec3(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]); }

// World point -> (pixel x, pixel y, normalized depth) for the view along `axis`.
vec3 project(vec3 p, int axis) {
    int ua = (axis + 1) % 3;
    int va = (axis + 2) % 3;
    return vec3((p[ua] - u_viewLo[ua]) * u_pixelScale[ua], (p[va] - u_viewLo[va]) * u_pixelScale[va],
                (p[axis] - u_viewLo[axis]) * u_depthScale[axis]);
}

void main() {
    int axis = gl_InstanceID;
    uint prim = uint(gl_VertexID) / 3u;
    int corner = gl_VertexID % 3;
    uvec2 entry = prims[prim];
    v_item = entry.y;
    v_owner = owners[entry.y];
    v_axis = axis;
    int ua = (axis + 1) % 3;
    int va = (axis + 2) % 3;
    vec2 hs = vec2(u_halfSize[ua], u_halfSize[va]);

    if ((entry.x & CULLIDE_PRIM_BOX_BIT) != 0u) {
        uint b = (entry.x & ~CULLIDE_PRIM_BOX_BIT) * 6u;
        vec3 lo = project(vec3(boxes[b], boxes[b + 1u], boxes[b + 2u]), axis);
        vec3 hi = project(vec3(boxes[b + 3u], boxes[b + 4u], boxes[b + 5u]), axis);
        v_rect = vec4(lo.xy, hi.xy);
        v_zrange = vec2(lo.z, hi.z);
        v_edge[0] = vec3(0.0, 0.0, -1.0);
        v_edge[1] = vec3(0.0, 0.0, -1.0);
        v_edge[2] = vec3(0.0, 0.0, -1.0);
        v_plane = vec4(0.0);
        v_origin = vec2(0.0);
    } else {
        uint t = entry.x * 3u;
        vec3 p0 = project(vertexAt(indices[t]), axis);
        vec3 p1 = project(vertexAt(indices[t + 1u]), axis);
        vec3 p2 = project(vertexAt(indices[t + 2u]), axis);
        v_rect = vec4(min(min(p0.xy, p1.xy), p2.xy), max(max(p0.xy, p1.xy), p2.xy));
        v_zrange = vec2(min(min(p0.z, p1.z), p2.z), max(max(p0.z, p1.z), p2.z));
        vec2 d1 = p1.xy - p0.xy;
        vec2 d2 = p2.xy - p0.xy;
        float area2 = d1.x * d2.y - d1.y * d2.x;
        float maxEdge2 = max(max(dot(d1, d1), dot(d2, d2)), dot(p2.xy - p1.xy, p2.xy - p1.xy));
        // Well-conditioned in 2D: exact edge tests and a depth plane. Otherwise (edge-on, needle-like or tiny
        // in projection) the rectangle and the triangle's own depth range are used: coarser, still conservative.
        bool wellShaped = abs(area2) > 1.0e-3 && abs(area2) >= maxEdge2 * (1.0 / 256.0);
        if (wellShaped) {
            float s = area2 > 0.0 ? 1.0 : -1.0;
            vec2 a[3] = vec2[3](p0.xy, p1.xy, p2.xy);
            for (int i = 0; i < 3; ++i) {
                vec2 e = a[(i + 1) % 3] - a[i];
                vec2 n = s * vec2(e.y, -e.x);
                v_edge[i] = vec3(n, -dot(n, a[i]));
            }
            float invArea = 1.0 / area2;
            float pa = ((p1.z - p0.z) * d2.y - (p2.z - p0.z) * d1.y) * invArea;
            float pb = ((p2.z - p0.z) * d1.x - (p1.z - p0.z) * d2.x) * invArea;
            v_plane = vec4(pa, pb, p0.z, 1.0);
            v_origin = p0.xy;
        } else {
            v_edge[0] = vec3(0.0, 0.0, -1.0);
            v_edge[1] = vec3(0.0, 0.0, -1.0);
            v_edge[2] = vec3(0.0, 0.0, -1.0);
            v_plane = vec4(0.0);
            v_origin = vec2(0.0);
        }
    }

    // A triangle covering the rectangle dilated by the half size (plus one pixel so that every pixel centre whose
    // square touches it lies inside in reliable mode).
    vec2 grow = u_conservative != 0 ? hs + vec2(1.0) : vec2(0.0);
    vec2 lo = v_rect.xy - grow;
    vec2 ext = (v_rect.zw + grow) - lo;
    vec2 corners[3] = vec2[3](lo, lo + vec2(2.0 * ext.x + 1.0, 0.0), lo + vec2(0.0, 2.0 * ext.y + 1.0));
    vec2 px = corners[corner];
    float width = float(3 * u_resolution);
    float height = float(u_resolution);
    gl_Position = vec4(((px.x + float(axis * u_resolution)) / width) * 2.0 - 1.0, (px.y / height) * 2.0 - 1.0,
                       0.0, 1.0);
}
