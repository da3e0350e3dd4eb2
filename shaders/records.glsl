// Primitive records of the raster back-end (written by cull_setup.comp, read by cull.vert and cull.frag).
layout(std430, binding = CULLIDE_SSBO_RECORDS) buffer Records { PrimRecord records[]; };
layout(std430, binding = CULLIDE_SSBO_COUNTERS) readonly buffer Counters { uint counters[]; };

// The records this iteration runs over (per view: the records of view a are a * recordCount() + index).
uint recordCount() { return counters[CULLIDE_DISPATCH_RECORDS]; }

PrimRecord toRecord(Prim p) {
    return PrimRecord(p.rect, vec4(p.edge0, 0.0), vec4(p.edge1, 0.0), vec4(p.edge2, 0.0), p.plane,
                      vec4(p.origin, p.zrange), uvec4(p.item, p.owner, uint(p.axis), 0u));
}

Prim fromRecord(PrimRecord r) {
    return Prim(r.rect, r.edge0.xyz, r.edge1.xyz, r.edge2.xyz, r.plane, r.originZrange.xy, r.originZrange.zw,
                r.ids.x, r.ids.y, int(r.ids.z));
}
