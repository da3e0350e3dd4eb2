// The start of a level described by its objects (LevelItems::objectRanges, plugin/src/PruningBackend.h), on the
// device: nothing per item and no view is sent. Per item (one invocation each), from its object's range: its primitive
// (a box of the upload, or a triangle of the mesh's spatial order), its owner, and whether it starts alive — where the
// level inherits, its parent survived the level before; and the box pre-pass keeps it: its box (a group's box, or the
// triangle's box of the positions) meets one of its partner objects' boxes grown by u_slack, or its range keeps every
// item (a proxy; an object with too many partners to test). The items that start alive are counted (with their owner
// range and boxes: gather.glsl), and the last work group fits the first view to them as an iteration's end fits the
// next (none alive: to the origin). Where the device exact stage follows the level, the groups of triangles whose
// parent survived are listed for it (by their first item), and the last work group writes its indirect arguments.
// ReferenceVisibility.cpp's startByObjects is the CPU's copy, float for float.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_ORDERED) readonly buffer Ordered { uint ordered[]; };
layout(std430, binding = CULLIDE_SSBO_PARENT_ALIVE) readonly buffer ParentState { uint parentState[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_OWNER) writeonly buffer Owners { uint owners[]; };
layout(std430, binding = CULLIDE_SSBO_ITEM_PRIMS) writeonly buffer ItemPrims { uint itemPrims[]; };
layout(std430, binding = CULLIDE_SSBO_ALIVE) writeonly buffer Alive { uint alive[]; };
layout(std430, binding = CULLIDE_SSBO_EXACT_ITEMS) writeonly buffer ExactItems { uint exactItems[]; };
layout(location = CULLIDE_LOC_RESOLUTION) uniform int u_resolution;
layout(location = CULLIDE_LOC_ITEM_BASE) uniform uint u_itemBase;
layout(location = CULLIDE_LOC_ITEM_COUNT) uniform uint u_itemCount;
layout(location = CULLIDE_LOC_GROUPS) uniform uint u_groups;  // of all of the start's dispatches
layout(location = CULLIDE_LOC_GROUP_SIZE) uniform uint u_groupSize;
layout(location = CULLIDE_LOC_INHERITS) uniform int u_inherits;
layout(location = CULLIDE_LOC_SLACK) uniform float u_slack;
layout(location = CULLIDE_LOC_CHUNKS) uniform uint u_chunks;

shared bool s_last;

// Whether this work group is the last of all of the start's to finish (every lane calls it).
bool lastToFinish() {
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationID.x == 0u) s_last = atomicAdd(counters[CULLIDE_CHAIN_SURVIVE_DONE], 1u) == u_groups - 1u;
    barrier();
    memoryBarrierBuffer();
    return s_last;
}

void main() {
    uint i = u_itemBase + gl_GlobalInvocationID.x;
    clearGroupCounters();
    barrier();
    if (i < u_itemCount) {
        uint r = rangeOf(i);
        uint j = i - field(r, CULLIDE_RANGE_ITEM_BEGIN);
        uint kind = field(r, CULLIDE_RANGE_KIND);
        bool isBox = (kind & 1u) == CULLIDE_RANGE_BOXES;
        uint first = field(r, CULLIDE_RANGE_FIRST);
        uint prim = isBox ? (first + j) | CULLIDE_PRIM_BOX_BIT : ordered[first + j];
        uint owner = field(r, CULLIDE_RANGE_OWNER);
        uint parent = field(r, CULLIDE_RANGE_PARENT) + (isBox ? j : j / u_groupSize);
        bool live = u_inherits == 0 || parentState[parent] != 0u;
        // The exact stage's work: a group of triangles whose parent survived, listed by its first item.
        if (u_chunks != 0u && live && !isBox && j % u_groupSize == 0u)
            exactItems[atomicAdd(counters[CULLIDE_CHAIN_STARTED], 1u)] = i;
        vec3 lo;
        vec3 hi;
        primBox(prim, lo, hi);
        if (live && (kind & CULLIDE_RANGE_KEEP) == 0u) {
            bool kept = false;
            uint end = field(r, CULLIDE_RANGE_PARTNER_END);
            uint partners = uint(CULLIDE_RANGE_WORDS) * u_rangeCount;
            for (uint p = field(r, CULLIDE_RANGE_PARTNER_BEGIN); p < end && !kept; ++p)
                kept = meetsGrownBox(lo, hi, ranges[partners + p], u_slack);
            live = kept;
        }
        itemPrims[i] = prim;
        owners[i] = owner;
        alive[i] = live ? 1u : 0u;
        if (live) {
            atomicOr(counters[CULLIDE_ALIVE_BITS + i / 32u], 1u << (i % 32u));
            gatherAlive(owner, uvec3(orderedBits(lo.x), orderedBits(lo.y), orderedBits(lo.z)),
                        uvec3(orderedBits(hi.x), orderedBits(hi.y), orderedBits(hi.z)));
        }
    }
    barrier();
    if (gl_LocalInvocationID.x == 0u) addGroupCounters();
    if (!lastToFinish() || gl_LocalInvocationID.x != 0u) return;
    uint started = counters[CULLIDE_COUNTER_ALIVE];
    counters[CULLIDE_CHAIN_ALIVE_START] = started;
    counters[CULLIDE_CHAIN_SURVIVE_DONE] = 0u;
    if (started == 0u) {  // nothing to fit: the view of the origin (the chain stops at its first iteration)
        uint origin = orderedBits(0.0);  // the axes written out (gather.glsl)
        counters[CULLIDE_COUNTER_LO + 0] = origin;
        counters[CULLIDE_COUNTER_LO + 1] = origin;
        counters[CULLIDE_COUNTER_LO + 2] = origin;
        counters[CULLIDE_COUNTER_HI + 0] = origin;
        counters[CULLIDE_COUNTER_HI + 1] = origin;
        counters[CULLIDE_COUNTER_HI + 2] = origin;
    }
    fitView(0u, counters[CULLIDE_COUNTER_OWNER_MAX], u_resolution);
    if (u_chunks != 0u) {  // the exact stage's work groups: 64 listed groups each (rows of at most 65,535), per chunk
        uint listed = counters[CULLIDE_CHAIN_STARTED];
        uint groups = (listed + uint(CULLIDE_COMPUTE_GROUP_SIZE) - 1u) / uint(CULLIDE_COMPUTE_GROUP_SIZE);
        uint x = min(groups, 65535u);
        counters[CULLIDE_DISPATCH_EXACT] = x;
        counters[CULLIDE_DISPATCH_EXACT + 1] = x == 0u ? 0u : u_chunks;
        counters[CULLIDE_DISPATCH_EXACT + 2] = x == 0u ? 0u : (groups + x - 1u) / x;
    }
}
