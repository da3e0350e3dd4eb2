// Snapshot renderer, vertex stage: one vertex per triangle corner (non-indexed), positions relative to the frame
// centre so that float keeps the precision of the double-precision scene near the region shown.

layout(location = CULLIDE_SNAPSHOT_ATTR_POSITION) in vec3 a_position;
layout(location = CULLIDE_SNAPSHOT_ATTR_COLOR) in vec4 a_color;
layout(location = CULLIDE_SNAPSHOT_LOC_VIEW_PROJ) uniform mat4 u_viewProj;

out vec3 v_position;
flat out vec4 v_color;
// Barycentric coordinates from the corner number: no extra vertex data for the edge lines. Draws start at a
// multiple of 3, so gl_VertexID % 3 is the corner.
out vec3 v_bary;

void main() {
    v_position = a_position;
    v_color = a_color;
    int corner = gl_VertexID % 3;
    v_bary = vec3(corner == 0 ? 1.0 : 0.0, corner == 1 ? 1.0 : 0.0, corner == 2 ? 1.0 : 0.0);
    gl_Position = u_viewProj * vec4(a_position, 1.0);
}
