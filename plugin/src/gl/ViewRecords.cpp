#include "gl/ViewRecords.h"

#include <cstring>

namespace cullide::gl {

float fromOrderedBits(std::uint32_t key) {
    const std::uint32_t bits = (key & 0x80000000u) != 0 ? (key & 0x7FFFFFFFu) : ~key;
    float f = 0.0f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

ViewRecord toViewRecord(const View& view, std::uint32_t idBits) {
    ViewRecord r{};
    for (int a = 0; a < 3; ++a) {
        r.boxMin[a] = view.box.min[a];
        r.boxMax[a] = view.box.max[a];
        r.lo[a] = view.lo[a];
        r.pixelScale[a] = view.pixelScale[a];
        r.depthScale[a] = view.depthScale[a];
        r.halfSize[a] = view.halfSize[a];
        r.depthPad[a] = view.depthPad[a];
    }
    r.idBits = idBits;
    return r;
}

IterationTrace toTrace(const ViewRecord& record) {
    IterationTrace t;
    for (int a = 0; a < 3; ++a) {
        t.view.box.min[a] = record.boxMin[a];
        t.view.box.max[a] = record.boxMax[a];
        t.view.lo[a] = record.lo[a];
        t.view.pixelScale[a] = record.pixelScale[a];
        t.view.depthScale[a] = record.depthScale[a];
        t.view.halfSize[a] = record.halfSize[a];
        t.view.depthPad[a] = record.depthPad[a];
        t.result.bounds.min[a] = fromOrderedBits(record.boundsLo[a]);
        t.result.bounds.max[a] = fromOrderedBits(record.boundsHi[a]);
    }
    t.idBits = record.idBits;
    t.result.alive = record.alive;
    t.result.ownerMin = record.ownerMin;
    t.result.ownerMax = record.ownerMax;
    t.result.overflows = record.overflows;
    return t;
}

}  // namespace cullide::gl
