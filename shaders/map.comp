// The mapped meshes' world positions (MappedMesh, plugin/src/PruningBackend.h): every vertex of a mesh given in its
// own frame, mapped by its transform as transformPoint (plugin/src/WorldMeshes.cpp) maps it on the CPU — the same
// double operations in the same order, none fused (precise) — then made relative to the upload origin and rounded to
// float, 0 where not finite (devicePosition): the positions ClusterGeometry would have written, bit for bit. One
// dispatch per upload, one invocation per mapped vertex (the meshes' vertices one after the other: a mesh finds its
// invocations by binary search over where each one's start), so many small meshes beside a large one cost their
// vertices only.
layout(local_size_x = CULLIDE_COMPUTE_GROUP_SIZE) in;
layout(std430, binding = CULLIDE_SSBO_POSITIONS) writeonly buffer Positions { float positions[]; };
layout(std430, binding = CULLIDE_SSBO_LOCAL) readonly buffer Local { double local[]; };
// Mirrored by MappedRecord (plugin/src/gl/LevelDevice.cpp).
struct MappedRecord {
    double m[12];     // the linear part row by row (m[3 * i + j] = row i, column j), then the translation
    uint localBase;   // its first vertex in local[] (3 doubles each)
    uint baseVertex;  // its first vertex in positions[] (3 floats each)
    uint count;
    uint firstMapped;  // its first invocation: the vertices of the records before it, summed
};
layout(std430, binding = CULLIDE_SSBO_MAPPED) readonly buffer Mapped { MappedRecord meshes[]; };
layout(location = CULLIDE_LOC_ORIGIN) uniform dvec3 u_origin;
layout(location = CULLIDE_LOC_MAPPED_BASE) uniform uint u_mappedBase;
layout(location = CULLIDE_LOC_MAPPED_MESHES) uniform uint u_meshCount;
layout(location = CULLIDE_LOC_MAPPED_VERTICES) uniform uint u_vertexCount;

// Row i of transformPoint: ((m_i0 * p0 + m_i1 * p1) + m_i2 * p2) + t_i, each operation rounded.
double row(uint mesh, int i, dvec3 p) {
    precise double x = meshes[mesh].m[3 * i] * p.x;
    x = x + meshes[mesh].m[3 * i + 1] * p.y;
    x = x + meshes[mesh].m[3 * i + 2] * p.z;
    x = x + meshes[mesh].m[9 + i];
    return x;
}

// The mesh of mapped vertex k: the last record whose firstMapped <= k.
uint meshOf(uint k) {
    uint lo = 0u;
    uint hi = u_meshCount;  // meshes[lo].firstMapped <= k < meshes[hi].firstMapped
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (meshes[mid].firstMapped <= k) lo = mid; else hi = mid;
    }
    return lo;
}

void main() {
    uint k = u_mappedBase + gl_GlobalInvocationID.x;
    if (k >= u_vertexCount) return;
    uint mesh = meshOf(k);
    uint v = k - meshes[mesh].firstMapped;
    uint l = 3u * (meshes[mesh].localBase + v);
    dvec3 p = dvec3(local[l], local[l + 1u], local[l + 2u]);
    // The three rows written out (NVIDIA's compiler and loops over indexed doubles: see iteration.glsl).
    precise dvec3 w = dvec3(row(mesh, 0, p), row(mesh, 1, p), row(mesh, 2, p));
    bool finite = !any(isnan(w)) && !any(isinf(w));
    precise dvec3 r = finite ? w - u_origin : dvec3(0.0);
    uint o = 3u * (meshes[mesh].baseVertex + v);
    positions[o] = float(r.x);
    positions[o + 1u] = float(r.y);
    positions[o + 2u] = float(r.z);
}
