// The C++ mirror of view.glsl's ViewRecord: a level's iteration views on the device (CULLIDE_SSBO_VIEWS). The C++
// side writes the first one; the work group that ends an iteration (iteration.glsl) fits each next one and adds what each iteration left,
// which a level's trace reads back (tests).
#pragma once

#include "PruningBackend.h"

#include <cstdint>

namespace cullide::gl {

/// std430 layout of view.glsl's ViewRecord.
struct ViewRecord {
    double boxMin[3];
    double boxMax[3];
    float lo[3];
    float pixelScale[3];
    float depthScale[3];
    float halfSize[3];
    float depthPad[3];
    std::uint32_t idBits;
    std::uint32_t alive;
    std::uint32_t ownerMin;
    std::uint32_t ownerMax;
    std::uint32_t overflows;
    std::uint32_t records;
    std::uint32_t stop;
    std::uint32_t boundsLo[3];  ///< order-preserving float bits (iteration.glsl)
    std::uint32_t boundsHi[3];
};
static_assert(sizeof(ViewRecord) == 160, "view.glsl's ViewRecord is 160 bytes in std430");

/// The record of a view fitted on the CPU (what iteration 0 reads).
ViewRecord toViewRecord(const View& view, std::uint32_t idBits);

/// An iteration as the device ran it: its view and what it left.
IterationTrace toTrace(const ViewRecord& record);

/// Inverse of the shaders' orderedBits.
float fromOrderedBits(std::uint32_t key);

}  // namespace cullide::gl
