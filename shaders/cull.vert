// Raster back-end, vertex stage. One triangle per (primitive, view axis) record, covering the primitive's rectangle
// grown by the tested square's half size plus one pixel, so that the rasterizer visits every pixel centre whose
// square may touch it; the fragment stage reads the record and does the exact test. Only the record index varies.

flat out uint v_record;

void main() {
    uint record = uint(gl_VertexID) / 3u;
    int axis = int(record / recordCount());
    v_record = record;
    vec4 rect = records[record].rect;
    vec2 grow = u_conservative != 0 ? halfSizeFor(axis) + vec2(1.0) : vec2(0.0);
    vec2 lo = rect.xy - grow;
    vec2 ext = (rect.zw + grow) - lo;
    int corner = gl_VertexID % 3;
    vec2 px = corner == 0 ? lo : (corner == 1 ? lo + vec2(2.0 * ext.x + 1.0, 0.0) : lo + vec2(0.0, 2.0 * ext.y + 1.0));
    // A disabled view or a pruned item: a degenerate triangle outside the target.
    if (!axisEnabled(axis) || alive[records[record].ids.x] == 0u) px = vec2(-4.0);
    float width = float(3 * u_resolution);
    gl_Position = vec4(((px.x + float(axis * u_resolution)) / width) * 2.0 - 1.0,
                       (px.y / float(u_resolution)) * 2.0 - 1.0, 0.0, 1.0);
}
