// The compute back-end's work per invocation (cull.comp, flag.comp), one per (primitive band, view axis): its share
// of the primitive's conservative footprint (every `bands`-th pixel, starting at `band`), with the same coverage test
// and per-pixel bookkeeping as the fragment stage. Needs view.glsl, common.glsl, visit.glsl and passes.glsl before it.

// The flag bits invocation (record `index`, view `axis`) earns its item: 0 outside the flag pass.
uint scan(uint index, int axis) {
    uint band = prims[index].z;
    uint bands = prims[index].w;
    Prim p = makePrim(index, axis);
    vec2 h = halfSizeFor(axis);
    // Pixel centres i + 0.5 whose square may touch the rectangle.
    // precise: every pass (separate programs) scans the same pixels, so the flag pass may trust the overflow count
    // of the nearest pass.
    precise vec2 from = p.rect.xy - h - vec2(0.5);
    precise vec2 to = p.rect.zw + h - vec2(0.5);
    // Clamped before the conversion to int, which is undefined out of range (as ReferenceVisibility's pixelIndex).
    vec2 span = vec2(float(u_resolution));
    ivec2 first = max(ivec2(clamp(floor(from), vec2(-1.0), span)), ivec2(0));
    ivec2 last = min(ivec2(clamp(ceil(to), vec2(-1.0), span)), ivec2(u_resolution - 1));
    if (last.x < first.x || last.y < first.y) return 0u;
    uint width = uint(last.x - first.x + 1);
    uint total = width * uint(last.y - first.y + 1);
    if (band >= total) return 0u;
    if ((total - band + bands - 1u) / bands > uint(CULLIDE_MAX_LOOP_ITERATIONS)) {
        atomicAdd(counters[CULLIDE_COUNTER_OVERFLOWS], 1u);
        return 0u;
    }
    uint bits = 0u;
    for (uint k = band; k < total; k += bands) {
        int x = first.x + int(k % width);
        int y = first.y + int(k / width);
        vec2 c = vec2(float(x) + 0.5, float(y) + 0.5);
        float zlo;
        float zhi;
        if (!coverage(p, c, h, zlo, zhi)) continue;
        bits |= visit(ivec2(x + axis * u_resolution, y), p.owner, axis, zlo, zhi);
    }
    return bits;
}
