// Packing the records of the items still alive into the other record buffer (the compute back-end's nearest pass,
// the raster back-end's survivor pass), in no particular order: every pass over them is order-independent (atomic
// min, max and or). Needs common.glsl (prims) and passes.glsl (counters) before it.
layout(std430, binding = CULLIDE_SSBO_PRIMS_OUT) writeonly buffer PrimsOut { uvec4 primsOut[]; };

shared uint s_kept;
shared uint s_keptBase;

// Record `index` is kept where `keep`: room for the work group's kept records taken with one atomic add
// (CULLIDE_COUNTER_RECORDS counts them). Every lane of the work group calls it.
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
