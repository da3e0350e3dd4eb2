/* Binding points, uniform locations and flag layout shared verbatim by the C++ code and every shader.
 * Valid as both C++ and GLSL: only #define and comments. */
#ifndef CULLIDE_SHADER_BINDINGS_H
#define CULLIDE_SHADER_BINDINGS_H

/* Shader storage buffers (std430). */
#define CULLIDE_SSBO_POSITIONS 0   /* float[3 * vertexCount]: xyz relative to the upload origin */
#define CULLIDE_SSBO_INDICES 1     /* uint[3 * triangleCount]: global vertex indices */
#define CULLIDE_SSBO_BOXES 2       /* float[6 * boxCount]: min xyz, max xyz relative to the upload origin */
#define CULLIDE_SSBO_PRIMS 3       /* uvec4[primCount]: (primitive reference | kind bit, item, band, bands) */
#define CULLIDE_SSBO_ITEM_OWNER 4  /* uint[itemCount]: owner (compact object id within the level) */
#define CULLIDE_SSBO_FLAGS 5       /* uint[itemCount]: per-view "not fully visible" bits, atomicOr */
#define CULLIDE_SSBO_RECORDS 6     /* PrimRecord[3 * records]: per (view axis, primitive) setup, raster back-end */
#define CULLIDE_SSBO_COUNTERS 7    /* uint[CULLIDE_ALIVE_BITS + (itemCount + 31) / 32]: per iteration, see
                                      * CULLIDE_COUNTER_*; then the record-sized passes' count and indirect arguments,
                                      * see CULLIDE_DISPATCH_*; then the alive set's bits, see CULLIDE_ALIVE_BITS */
#define CULLIDE_SSBO_ALIVE 8       /* uint[itemCount]: 1 = the item is still in the level's set (kept on the device) */
#define CULLIDE_SSBO_ITEM_BOUNDS 9 /* uint[8 * itemCount]: item boxes (build.comp), order-preserving float bits: min xyz
                                      * of every item (3 per item), then max xyz of every item; then each item's records
                                      * (build.comp, cleared before every build); then the compute back-end's flag
                                      * pass's invocations done over it in the current iteration (cleared before every
                                      * iteration) */
#define CULLIDE_SSBO_PRIMS_OUT 10  /* uvec4[primCount]: the records of the items still alive, packed (survive.comp, or
                                      * the compute back-end's nearest pass) */
/* The record build (build.comp): */
#define CULLIDE_SSBO_PRIM_BEGIN 11 /* uint[itemCount + 1]: item i's primitives: ITEM_PRIMS[begin[i] .. begin[i + 1]) */
#define CULLIDE_SSBO_ITEM_PRIMS 12 /* uint[itemPrimCount]: primitive references (triangle, or box | PRIM_BOX_BIT) */
#define CULLIDE_SSBO_BANDS 13      /* uint[itemPrimCount]: each primitive's footprint (float bits), then its bands */
#define CULLIDE_SSBO_BUILD 14      /* uint[CULLIDE_BUILD_GROUPS + work groups]: see CULLIDE_BUILD_* */
#define CULLIDE_SSBO_VIEWS 15      /* ViewRecord[CULLIDE_MAX_ITERATIONS + 1] (view.glsl): iteration i's view (the first
                                      * written by the C++ side or start.comp, each next one where the iteration
                                      * before ends) and what the iteration left */
#define CULLIDE_SSBO_RANGES 16     /* uint[]: a level described by its objects (start.comp): its ranges'
                                      * records, then their partners' boxes (CULLIDE_RANGE_*) */
#define CULLIDE_SSBO_PARENT_ALIVE 17 /* uint[parents]: the last level's alive set (a copy), where a level inherits it */
/* The mapped meshes (map.comp): a rigid mesh's own vertices stay on the device, its transform is sent per upload. */
#define CULLIDE_SSBO_LOCAL 19      /* double[3 * local vertices]: the mapped meshes' vertices in their own frames */
#define CULLIDE_SSBO_MAPPED 20     /* MappedRecord[mapped meshes] (map.comp): transform, where its vertices are */
#define CULLIDE_SSBO_ORDERED 21    /* uint[triangleCount]: each mesh's triangles in its spatial order (global indices;
                                      * GpuGeometry::ordered), kept between uploads like the indices */
/* The boxes built on the device (group_boxes.comp): the groups of the meshes that move or deform. */
#define CULLIDE_SSBO_BOX_RANGES 18 /* uint[2 * built boxes]: per box, its group's first triangle in CULLIDE_SSBO_ORDERED
                                      * and its triangle count (GpuGeometry::builtRanges), kept between uploads */

/* The device exact stage (exact.comp), after a deferred triangle level: */
#define CULLIDE_SSBO_EXACT 22      /* uint[1 + 2 * capacity]: word 0 counts the frame's pairs (past the capacity too;
                                      * cleared at the frame's first exact stage), then per pair the two items, the
                                      * second | CULLIDE_EXACT_WITHIN where the filter certified it */
#define CULLIDE_SSBO_EXACT_ITEMS 23 /* uint[items]: where the exact stage follows a level, the groups of triangles
                                       * whose parent survived, by their first item, appended by start.comp
                                       * (exact.comp runs over those) */

/* Counters, reset before every iteration (and before start.comp, which gathers the items that start alive in them). */
#define CULLIDE_COUNTER_OVERFLOWS 0 /* compute invocations that would exceed CULLIDE_MAX_LOOP_ITERATIONS */
#define CULLIDE_COUNTER_ALIVE 1     /* items alive after the iteration (iteration.glsl) */
#define CULLIDE_COUNTER_OWNER_MIN 2 /* smallest and largest owner id among them */
#define CULLIDE_COUNTER_OWNER_MAX 3
#define CULLIDE_COUNTER_LO 4        /* 3 entries: min xyz of their boxes, as order-preserving float bits */
#define CULLIDE_COUNTER_HI 7        /* 3 entries: max xyz of their boxes, likewise */
#define CULLIDE_COUNTER_RECORDS 10  /* records kept, packed into CULLIDE_SSBO_PRIMS_OUT: those of the items still
                                     * alive (survive.comp), or (cull.comp's nearest pass) alive at the iteration's
                                     * start, which its second and flag passes run over */
#define CULLIDE_COUNTER_PRUNED 11   /* items the iteration pruned (with CULLIDE_COUNTER_ALIVE: every item decided) */
#define CULLIDE_COUNTER_COUNT 12   /* the counters the C++ side resets before every iteration and start.comp */

/* After the counters, in the same buffer (one read-back returns both): what the record-sized passes of the next
 * iteration (cull.comp, or cull_setup.comp, the draws and survive.comp) run over, dispatched indirectly. Written by
 * build.comp after a record build (the C++ side never waits for the count), otherwise by the work group that ends the
 * iteration before (iteration.glsl). */
#define CULLIDE_DISPATCH_RECORDS 16 /* records the passes run over */
#define CULLIDE_DISPATCH_NEEDED 17  /* records the last build needed (its total, written even when they did not fit);
                                     * APPEND's work groups reserve their room from it (reset before a build) */
#define CULLIDE_DISPATCH_NEEDED_APPROX 18 /* float bits: an upper bound of the total that cannot wrap around */
#define CULLIDE_DISPATCH_SHORT 19   /* 1: the last build needed more records than the buffers hold; none were written,
                                     * nothing runs over them and the iteration prunes nothing (the C++ side grows the
                                     * buffers and runs it again) */
#define CULLIDE_DISPATCH_CULL 20    /* 3 uints: glDispatchComputeIndirect arguments (x, 3 views, z) */
#define CULLIDE_DISPATCH_BUILD_DONE 23 /* APPEND's work groups that have finished (reset before a build) */
#define CULLIDE_DISPATCH_SURVIVE 24 /* 3 uints: (x, 1, z) over the larger of the items and the records */
#define CULLIDE_DISPATCH_NEEDED_HI 27 /* the total in units of 256, rounded up per work group (reset before a build) */
#define CULLIDE_DISPATCH_DRAW 28    /* 4 uints: glDrawArraysIndirect's (9 vertices per record, 1, 0, 0) */
#define CULLIDE_COUNTERS_SIZE 32
/* Then the level's chain of iterations, kept across them (the C++ side issues a level's iterations without waiting;
 * the work group that ends an iteration, iteration.glsl, decides whether the next one runs and fits its view): */
#define CULLIDE_CHAIN_RAN 32        /* iterations run (the last one's index + 1) */
#define CULLIDE_CHAIN_STOP 33       /* CULLIDE_STOP_*: why the chain stopped after the last iteration run */
#define CULLIDE_CHAIN_SURVIVE_DONE 34 /* work groups of the pass that ends the iteration (or of start.comp) that
                                       * have finished (the last one resets it) */
#define CULLIDE_CHAIN_RECORDS_RUN 35  /* records the level's iterations ran over, summed */
#define CULLIDE_CHAIN_RECORDED_VIEW 36 /* the view the records were built for (build.comp's APPEND or SINGLE pass) */
#define CULLIDE_CHAIN_ALIVE_START 37 /* items alive at the level's start (all, or those start.comp keeps) */
#define CULLIDE_CHAIN_MISCOUNTED 39 /* 1: an iteration decided fewer or more items than were alive at its start (a
                                     * device fault: the C++ side throws BackendError) */
#define CULLIDE_CHAIN_PER_BAND 38   /* short bands: the pixels per band the level's last build found (float bits): the
                                     * estimate of the next build in the level's place (CULLIDE_LOC_PER_BAND) */
#define CULLIDE_CHAIN_STARTED 40   /* groups start.comp appended to CULLIDE_SSBO_EXACT_ITEMS */
#define CULLIDE_DISPATCH_EXACT 41  /* 3 uints: exact.comp's indirect arguments (x, chunks, z: start.comp's last work
                                    * group, for the groups it listed) */
#define CULLIDE_CHAIN_ALIVE 48      /* CULLIDE_MAX_ITERATIONS words: items alive after iteration i */
#define CULLIDE_MAX_ITERATIONS 64   /* Settings::maxIterations at most */
/* Then words CULLIDE_DISPATCH_RECORDS .. CULLIDE_AHEAD of the level run before this one without being waited for
 * (copied there before the read-back: one read-back brings both levels' chains). */
#define CULLIDE_AHEAD 112
/* Then the level's alive set, one bit per item (item i: bit i % 32 of word CULLIDE_ALIVE_BITS + i / 32): set at the
 * level's start (by the C++ side, or by start.comp in a level described by its objects), cleared as
 * items leave. The level's one read-back brings it all. */
#define CULLIDE_ALIVE_BITS 208

/* Why a level's chain of iterations stopped (CULLIDE_CHAIN_STOP). */
#define CULLIDE_STOP_NONE 0      /* it did not: the next iteration runs */
#define CULLIDE_STOP_DONE 1      /* the set did not change (or the iteration pruned nothing: an overflow, short
                                  * records), none is left, the iteration pruned too few (Settings::minPruneFraction)
                                  * or the last iteration allowed ran */
#define CULLIDE_STOP_ONE_OWNER 2 /* one owner is left: nothing to collide with, every item is pruned */
#define CULLIDE_STOP_REFIT 3     /* the next view shrank to a quarter of the records' along some axis: the C++ side
                                  * builds them again for it and goes on */

/* The record build's buffer. Per work group g of the FOOTPRINTS pass, CULLIDE_BUILD_GROUPS + g holds its footprint
 * sum (float bits). */
#define CULLIDE_BUILD_PER_BAND 0   /* pixels per band (float bits, FOOTPRINTS' last work group) */
#define CULLIDE_BUILD_FOOTPRINTS_DONE 1 /* FOOTPRINTS' work groups that have finished (reset before a build) */
#define CULLIDE_BUILD_GROUPS 4

/* Passes of build.comp (CULLIDE_LOC_PASS). */
#define CULLIDE_BUILD_PASS_FOOTPRINTS 0 /* per primitive: its largest footprint (short bands only); the last work
                                         * group: pixels per band */
#define CULLIDE_BUILD_PASS_APPEND 1     /* per primitive: its records, appended; the last work group: the dispatch */
#define CULLIDE_BUILD_PASS_SINGLE 2     /* FOOTPRINTS' per-primitive work and APPEND in one pass, where the pixels per
                                         * band are given (CULLIDE_LOC_PER_BAND: long bands, or short ones estimated
                                         * from the last build in the level's place) or there are no bands */

/* Per-pixel images (r32ui), three views side by side: width 3 * resolution, height resolution. */
#define CULLIDE_IMAGE_NEAR1 0  /* min over items of (quantized nearest depth << idBits | owner) */
#define CULLIDE_IMAGE_FAR1 1   /* max over items of (quantized farthest depth + 1 << idBits | owner) */
#define CULLIDE_IMAGE_NEAR2 2  /* like NEAR1 over owners other than NEAR1's owner */
#define CULLIDE_IMAGE_FAR2 3   /* like FAR1 over owners other than FAR1's owner */

/* Uniform locations. */
#define CULLIDE_LOC_PASS 0          /* int: CULLIDE_PASS_* */
#define CULLIDE_LOC_RESOLUTION 1    /* int */
/* 2-7: unused (the view is in CULLIDE_SSBO_VIEWS) */
#define CULLIDE_LOC_CONSERVATIVE 8  /* int: 1 = reliable mode, 0 = sampled */
#define CULLIDE_LOC_PRIM_COUNT 9    /* uint: build.comp: the level's primitives */
#define CULLIDE_LOC_AXES 10         /* uint: bit mask of the view axes in use (x = 1, y = 2, z = 4) */
#define CULLIDE_LOC_PRIM_BASE 11    /* uint: build.comp: first primitive of this dispatch (split at the group-count
                                     * limit) */
#define CULLIDE_LOC_REQUIRED 12     /* uint: iteration.glsl: the flag bits an item needs to stay alive */
#define CULLIDE_LOC_BANDS 13        /* int: build.comp: CULLIDE_BANDS_* */
#define CULLIDE_LOC_GROUPS 14       /* uint: build.comp: work groups of its per-primitive passes */
#define CULLIDE_LOC_ITEM_COUNT 15   /* uint: build.comp: the level's items */
#define CULLIDE_LOC_CAPACITY 16     /* uint: build.comp: records the record buffers hold */
#define CULLIDE_LOC_MAX_GROUPS 17   /* uint: build.comp: GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] (indirect arguments) */
#define CULLIDE_LOC_WITH_BOUNDS 18  /* int: build.comp: 1 = the first pass (FOOTPRINTS, SINGLE) builds the items' boxes */
#define CULLIDE_LOC_ITERATION 19    /* uint: the iteration whose view the passes use (views[u_iteration]) */
#define CULLIDE_LOC_MAX_ITERATIONS 20 /* uint: iteration.glsl: Settings::maxIterations */
#define CULLIDE_LOC_MARGIN 21       /* double: iteration.glsl: Settings::margin (the next view's fit) */
#define CULLIDE_LOC_COORDINATE_BOUND 22 /* double: iteration.glsl: GpuGeometry::coordinateBound */
#define CULLIDE_LOC_MIN_PRUNE_FRACTION 23 /* double: iteration.glsl: Settings::minPruneFraction */
#define CULLIDE_LOC_ONE_PRIM_EACH 25 /* int: build.comp: 1 = item i is primitive i (CULLIDE_SSBO_PRIM_BEGIN not sent) */
#define CULLIDE_LOC_ORIGIN 27       /* dvec3: map.comp: the upload origin (world) */
#define CULLIDE_LOC_MAPPED_BASE 28  /* uint: map.comp: the first mapped vertex of this dispatch (split at the
                                     * group-count limit) */
#define CULLIDE_LOC_MAPPED_MESHES 31   /* uint: map.comp: the mapped meshes (records) */
#define CULLIDE_LOC_MAPPED_VERTICES 32 /* uint: map.comp: their vertices, summed */
#define CULLIDE_LOC_PER_BAND 33     /* float: build.comp's SINGLE pass: pixels per band (CULLIDE_PIXELS_PER_INVOCATION
                                     * for long bands; for short ones an estimate from the last build in the place) */
#define CULLIDE_LOC_RANGES 38       /* uint: start.comp: the level's object ranges (CULLIDE_SSBO_RANGES) */
#define CULLIDE_LOC_GROUP_SIZE 39   /* uint: start.comp: triangles per parent (Settings::groupSize) */
#define CULLIDE_LOC_INHERITS 40     /* int: start.comp: 1 = an item starts alive only where its parent survived */
#define CULLIDE_LOC_SLACK 41        /* float: start.comp: the box pre-pass's slack (LevelItems::prepassSlack) */
#define CULLIDE_LOC_ITEM_BASE 42    /* uint: start.comp: the first item of this dispatch (split at the group-count
                                     * limit) */
#define CULLIDE_LOC_BOX_BASE 34     /* uint: group_boxes.comp: the first built box of this dispatch (split at the
                                     * group-count limit) */
#define CULLIDE_LOC_BOX_FIRST 35    /* uint: group_boxes.comp: where the built boxes start (after the uploaded ones) */
#define CULLIDE_LOC_BOX_COUNT 36    /* uint: group_boxes.comp: the built boxes */
#define CULLIDE_LOC_BOX_INFLATE 37  /* float: group_boxes.comp: GpuGeometry::builtInflate */
#define CULLIDE_LOC_EXACT_PARTNERS 43 /* uint: exact.comp: where each range's exact partners begin in
                                       * CULLIDE_SSBO_RANGES (ranges + 1 words), the partner ranges after them */
#define CULLIDE_LOC_REACH 44        /* float: exact.comp: the filter's reach (0: margin 0; DeviceExactFilter.h) */
#define CULLIDE_LOC_FILTER 45       /* int: exact.comp: 1 = the filter decides what it can; 0 = every candidate is
                                     * written undecided (Settings::exactTriangles off) */
#define CULLIDE_LOC_CHUNKS 46       /* uint: start.comp: chunks of partner items per item where the exact stage follows
                                     * (0: it does not) */
#define CULLIDE_LOC_CHUNK_ITEMS 48  /* uint: exact.comp: partner items per chunk (ExactRequest::chunkItems) */
#define CULLIDE_LOC_EXACT_CAPACITY 47 /* uint: exact.comp: the pairs CULLIDE_SSBO_EXACT holds */
#define CULLIDE_EXACT_WITHIN 0x80000000u /* an exact pair the filter certified (its triangles intersect) */
#define CULLIDE_RANGE_WORDS 8
#define CULLIDE_RANGE_ITEM_BEGIN 0    /* its first item */
#define CULLIDE_RANGE_COUNT 1         /* its items */
#define CULLIDE_RANGE_FIRST 2         /* its first item's box (boxes), or where its triangles start in ORDERED */
#define CULLIDE_RANGE_PARENT 3        /* (inheriting) its first item's parent */
#define CULLIDE_RANGE_PARTNER_BEGIN 4 /* its partners' boxes, after the records: [begin, end) */
#define CULLIDE_RANGE_PARTNER_END 5
#define CULLIDE_RANGE_OWNER 6
#define CULLIDE_RANGE_KIND 7          /* CULLIDE_RANGE_BOXES or _TRIANGLES, | CULLIDE_RANGE_KEEP */
#define CULLIDE_RANGE_BOXES 0u        /* item j: box FIRST + j; its parent PARENT + j */
#define CULLIDE_RANGE_TRIANGLES 1u    /* item j: triangle ORDERED[FIRST + j]; its parent PARENT + j / group size */
#define CULLIDE_RANGE_KEEP 2u         /* the box pre-pass keeps every item (a proxy; too many partners to test) */

#define CULLIDE_BANDS_NONE 0        /* one record per primitive (raster back-end) */
#define CULLIDE_BANDS_LONG 1        /* bands of CULLIDE_PIXELS_PER_INVOCATION pixels (software renderers) */
#define CULLIDE_BANDS_SHORT 2       /* bands for about CULLIDE_TARGET_INVOCATIONS records (hardware GPUs) */

#define CULLIDE_COMPUTE_GROUP_SIZE 64 /* local_size_x of cull.comp */
/* The record build splits a primitive's footprint into bands of at most this many pixels per compute invocation (on
 * a hardware GPU far fewer: enough bands to fill the device, see build.comp)... */
#define CULLIDE_PIXELS_PER_INVOCATION 4096
/* ...on a hardware GPU bands as short as needed for about this many records, but at least this many pixels. */
#define CULLIDE_TARGET_INVOCATIONS 131072.0
#define CULLIDE_MIN_PIXELS_PER_INVOCATION 32.0
/* ...so no invocation comes near llvmpipe's limit of 65535 loop iterations per invocation (shared by all loops;
 * past it loops silently stop). An invocation that would still exceed this bound does nothing and counts itself
 * in CULLIDE_COUNTER_OVERFLOWS; that iteration prunes nothing (conservative) and the level ends. */
#define CULLIDE_MAX_LOOP_ITERATIONS 60000

#define CULLIDE_PASS_NEAREST 0  /* write NEAR1 / FAR1 */
#define CULLIDE_PASS_SECOND 1   /* write NEAR2 / FAR2 for owners other than the nearest/farthest one */
#define CULLIDE_PASS_FLAG 2     /* set FLAGS bits */

#define CULLIDE_PRIM_BOX_BIT 0x80000000u /* set in a primitive reference that names a box */

/* Flag bits: bit (2 * axis) = not fully visible from the -axis side (near test), bit (2 * axis + 1) = from the
 * +axis side (far test). An item survives an iteration when both bits of every enabled axis are set. */

/* Snapshot renderer (snapshot.vert / snapshot.frag, plugin/src/gl/SnapshotRenderer.cpp): a separate program, so its
 * locations may reuse the numbers above. One interleaved vertex per triangle corner (non-indexed draw): */
#define CULLIDE_SNAPSHOT_ATTR_POSITION 0    /* vec3: position relative to the frame centre (float) */
#define CULLIDE_SNAPSHOT_ATTR_COLOR 1       /* vec4 from RGBA8 unorm: rgb = colour, a = 1 - fade toward background */
#define CULLIDE_SNAPSHOT_LOC_VIEW_PROJ 0    /* mat4 (locations 0-3): frame-centre-relative world -> clip */
#define CULLIDE_SNAPSHOT_LOC_LIGHT 4        /* vec3: unit light direction (toward the light), world axes */
#define CULLIDE_SNAPSHOT_LOC_BACKGROUND 5   /* vec3: background colour (faded triangles blend toward it) */
#define CULLIDE_SNAPSHOT_LOC_EDGES 6        /* float: darkening of triangle edges, 0 = none */

#endif
