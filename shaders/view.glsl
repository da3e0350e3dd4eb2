// The views of a level's iterations (CULLIDE_SSBO_VIEWS): views[i] is what iteration i's passes read (u_iteration),
// written for the first iteration by the C++ side (fitView) or, in a level described by its objects, by start.comp's
// last work group, and by the work group that ends the iteration before (iteration.glsl) for each next one (the same fit in double, operation for operation); after the iteration that work
// group adds what it left. Mirrored by plugin/src/gl/ViewRecords.h.
struct ViewRecord {
    double boxMin[3];     // the view box (relative to the upload origin)
    double boxMax[3];
    float lo[3];          // View: box minimum, pixels and normalized depth per unit, reliable mode's square and pad
    float pixelScale[3];
    float depthScale[3];
    float halfSize[3];
    float depthPad[3];
    uint idBits;          // low bits of the packed depth that hold the owner id
    uint alive;           // after the iteration: the items alive, their owner range, the compute invocations that
    uint ownerMin;        // overflowed, the records it ran over and why the chain stopped (CULLIDE_STOP_*)
    uint ownerMax;
    uint overflows;
    uint records;
    uint stop;
    uint boundsLo[3];     // the alive items' boxes, as order-preserving float bits
    uint boundsHi[3];
};

layout(std430, binding = CULLIDE_SSBO_VIEWS) buffer Views { ViewRecord views[]; };
layout(location = CULLIDE_LOC_ITERATION) uniform uint u_iteration;
