// Snapshot renderer, fragment stage: flat Lambert shading from the triangle's own plane (screen-space derivatives
// of the position, so the vertices need no normals), lit from both sides because meshes are open soups; a little
// ambient; thin darker edges on triangles that are large on screen; faded triangles blended toward the background.

layout(location = CULLIDE_SNAPSHOT_LOC_LIGHT) uniform vec3 u_light;
layout(location = CULLIDE_SNAPSHOT_LOC_BACKGROUND) uniform vec3 u_background;
layout(location = CULLIDE_SNAPSHOT_LOC_EDGES) uniform float u_edges;

in vec3 v_position;
flat in vec4 v_color;
in vec3 v_bary;

layout(location = 0) out vec4 o_color;

const float kAmbient = 0.3;

void main() {
    vec3 n = cross(dFdx(v_position), dFdy(v_position));
    float len = length(n);
    // A triangle seen exactly edge-on has no usable plane here: draw it fully lit rather than with a NaN.
    float lambert = len > 1e-30 ? abs(dot(n / len, u_light)) : 1.0;
    vec3 c = v_color.rgb * (kAmbient + (1.0 - kAmbient) * lambert);

    // Distance to the nearest edge in pixels; the line fades out on triangles under ~8 pixels high, where it would
    // turn a dense mesh dark instead of outlining anything.
    vec3 w = max(fwidth(v_bary), vec3(1e-6));
    vec3 px = v_bary / w;
    float distance = min(px.x, min(px.y, px.z));
    float size = 1.0 / max(w.x, max(w.y, w.z));
    float edge = (1.0 - smoothstep(0.5, 1.5, distance)) * smoothstep(4.0, 12.0, size);
    c *= 1.0 - u_edges * edge;

    o_color = vec4(mix(u_background, c, v_color.a), 1.0);
}
