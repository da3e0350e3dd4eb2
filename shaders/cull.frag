// Raster back-end, fragment stage: the three views lie side by side in one 3*res x res target.

flat in uint v_record;

void main() {
    Prim p = fromRecord(records[v_record]);
    vec2 c = gl_FragCoord.xy - vec2(float(p.axis * u_resolution), 0.0);
    if (c.x < 0.0 || c.x >= float(u_resolution)) discard;  // belongs to a neighbouring view
    float zlo;
    float zhi;
    if (!coverage(p, c, halfSizeFor(p.axis), zlo, zhi)) discard;
    setFlags(p.item, visit(ivec2(gl_FragCoord.xy), p.owner, p.axis, zlo, zhi));
}
