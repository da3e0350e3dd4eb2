// A level described by its objects (LevelItems::objectRanges) as the device reads it: its ranges' records, then
// their partners' boxes, then (the device exact stage) each range's exact partners (CULLIDE_RANGE_*). Shared by a
// level's start (start.comp) and the exact stage (exact.comp).
layout(std430, binding = CULLIDE_SSBO_RANGES) readonly buffer Ranges { uint ranges[]; };
layout(location = CULLIDE_LOC_RANGES) uniform uint u_rangeCount;

uint field(uint range, int word) { return ranges[uint(CULLIDE_RANGE_WORDS) * range + uint(word)]; }

// The range of item i: the last r with ITEM_BEGIN <= i.
uint rangeOf(uint i) {
    uint lo = 0u;
    uint hi = u_rangeCount;  // field(lo) <= i < field(hi)
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (field(mid, CULLIDE_RANGE_ITEM_BEGIN) <= i) lo = mid; else hi = mid;
    }
    return lo;
}
