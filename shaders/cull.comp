// Compute back-end: one invocation per (primitive band, view axis) scans its share of the primitive's conservative
// footprint (every `bands`-th pixel, starting at `band`) and runs the same coverage test and per-pixel bookkeeping as
// the fragment stage. On llvmpipe this runs on every core (the raster back-end's vertex stage is single-threaded);
// on a GPU it avoids the fixed-function path. Dispatched indirectly (CULLIDE_DISPATCH_CULL): work groups along x and
// z, the view along y. An iteration is these three passes, with no survivor pass:
//   - the nearest pass runs over the records the last iteration ran over and packs those of the items still alive
//     into the other record buffer (CULLIDE_SSBO_PRIMS_OUT; CULLIDE_COUNTER_RECORDS of them): the second and flag
//     passes run over these only, so that a pruned item's record costs no lane of theirs.
//   - in the flag pass each invocation counts itself done for its item (CULLIDE_SSBO_ITEM_BOUNDS), and the item's
//     last one, which sees all of its flags, decides its fate; the last work group ends the iteration
//     (iteration.glsl).
// The second and flag passes are dispatched over as many work groups as the nearest pass: those past the packed
// records do nothing.

layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_PRIMS_OUT) writeonly buffer PrimsOut { uvec4 primsOut[]; };

shared uint s_kept;
shared uint s_keptBase;

// The flag bits invocation (record `index`, view `axis`) earns its item: 0 outside the flag pass.
uint scan(uint index, int axis) {
    uint band = prims[index].z;
    uint bands = prims[index].w;
    Prim p = makePrim(index, axis);
    vec2 h = halfSizeFor(axis);
    // Pixel centres i + 0.5 whose square may touch the rectangle.
    ivec2 first = max(ivec2(floor(p.rect.xy - h - vec2(0.5))), ivec2(0));
    ivec2 last = min(ivec2(ceil(p.rect.zw + h - vec2(0.5))), ivec2(u_resolution - 1));
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

// Whether this is the last of the flag pass's invocations over `item` (its records times the enabled views): all of
// its flags are in. It leaves the item's count at 0 for the next iteration.
bool lastForItem(uint item) {
    memoryBarrierBuffer();
    uint expected = bounds[6u * u_itemCount + item] * uint(bitCount(u_axes & 7u));
    if (atomicAdd(bounds[7u * u_itemCount + item], 1u) + 1u != expected) return false;
    bounds[7u * u_itemCount + item] = 0u;
    memoryBarrierBuffer();
    return true;
}

// The nearest pass's packing (every lane of a work group along the first view): record `index` is kept where `keep`.
void keepRecord(uint index, bool keep) {
    uint lane = gl_LocalInvocationID.x;
    if (lane == 0u) s_kept = 0u;
    barrier();
    uint slot = keep ? atomicAdd(s_kept, 1u) : 0u;
    barrier();
    if (lane == 0u && s_kept != 0u) s_keptBase = atomicAdd(counters[CULLIDE_COUNTER_RECORDS], s_kept);
    barrier();
    if (keep) primsOut[s_keptBase + slot] = prims[index];
}

void main() {
    uint index = (gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
                 gl_LocalInvocationID.x;
    int axis = int(gl_GlobalInvocationID.y);
    bool nearest = u_pass == CULLIDE_PASS_NEAREST;
    // The nearest pass's records are the last iteration's; the second and flag passes run over those it packed.
    uint records = nearest ? counters[CULLIDE_DISPATCH_RECORDS] : counters[CULLIDE_COUNTER_RECORDS];
    bool live = index < records && primAlive(index);
    if (nearest && gl_WorkGroupID.y == 0u) keepRecord(index, live);
    bool counted = live && axisEnabled(axis);
    uint bits = counted ? scan(index, axis) : 0u;
    if (u_pass != CULLIDE_PASS_FLAG) return;  // the same for the whole dispatch: no barrier below is skipped
    uint item = counted ? prims[index].y : 0u;
    if (counted) setFlags(item, bits);
    clearGroupCounters();
    barrier();
    if (counted && lastForItem(item)) decideItem(item);
    barrier();
    if (gl_LocalInvocationID.x == 0u) addGroupCounters();
    if (!lastGroupToFinish() || gl_LocalInvocationID.x != 0u) return;
    finishIteration(records, records, 0u);
}
