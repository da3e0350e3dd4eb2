#include "narrowphase/NarrowPhaseContext.h"

#include "broadphase/PairRecords.h"

namespace cullide::bullet {

const PairTriangles* NarrowPhaseContext::recordFor(const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1, bool& swapped) const {
    swapped = false;
    return records != nullptr ? records->find(w0, w1, swapped) : nullptr;
}

}  // namespace cullide::bullet
