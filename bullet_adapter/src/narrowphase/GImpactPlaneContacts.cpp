#include "narrowphase/GImpactPlaneContacts.h"

#include <BulletCollision/Gimpact/btBoxCollision.h>

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__SSE2__) && !defined(BT_USE_DOUBLE_PRECISION)
#include <emmintrin.h>
#endif

namespace cullide::bullet {

PlaneFilter::PlaneFilter(const btTransform& partTransform, const btVector3& scaling, const btVector4& equation,
                         btScalar margin) {
    // Bullet's distance of stored vertex f: w = B (f * s) + o, then w . n - constant - margin, all in btScalar. In
    // exact arithmetic that is sum_j (B^T n)_j s_j f_j + (o . n - constant - margin), which this filter computes in
    // btScalar too (the constants in double first). Each rounding of either is of a value bounded by
    // |n_i| (sum_j |B_ij| |s_j f_j| + |o_i|), |constant| or |margin|: some 9 epsilons of their sum bound both
    // (GImpactPlane.TheFilterNeverRulesOutAVertexBulletPutsBelowThePlane fails with a bound of 1/4, passes with 1),
    // 32 leave a wide margin.
    const double eps = 32.0 * std::numeric_limits<btScalar>::epsilon();
    const btMatrix3x3& basis = partTransform.getBasis();
    const btVector3& origin = partTransform.getOrigin();
    double normal[3] = {0.0, 0.0, 0.0}, error[3] = {0.0, 0.0, 0.0};
    double offset = -double(equation[3]) - double(margin);
    double errorOffset = std::fabs(double(equation[3])) + std::fabs(double(margin));
    for (int i = 0; i < 3; ++i) {
        const double n = equation[i];
        for (int j = 0; j < 3; ++j) {
            normal[j] += n * double(basis[i][j]) * double(scaling[j]);
            error[j] += std::fabs(n * double(basis[i][j]) * double(scaling[j]));
        }
        offset += n * double(origin[i]);
        errorOffset += std::fabs(n * double(origin[i]));
    }
    for (int j = 0; j < 3; ++j) {
        m_normal[j] = btScalar(normal[j]);
        m_error[j] = btScalar(eps * error[j]);
    }
    m_offset = btScalar(offset);
    m_errorOffset = btScalar(eps * errorOffset);
}

btVector4 planeEquation(const btStaticPlaneShape& plane, const btTransform& planeTransform) {
    // btPlaneShape::get_plane_equation_transformed (btGImpactCollisionAlgorithm.cpp), with the shape's public getters.
    const btVector3 normal = planeTransform.getBasis() * plane.getPlaneNormal();
    return btVector4(normal[0], normal[1], normal[2],
                     normal.dot(planeTransform * (plane.getPlaneConstant() * plane.getPlaneNormal())));
}

namespace {

/// Bullet's test of one vertex (gimpacttrimeshpart_vs_plane_collision's loop body): same operations, same order.
void testVertex(const btGImpactMeshShapePart& part, int index, const btTransform& transform, const btVector4& equation,
                btScalar margin, const PlanePointSink& add) {
    btVector3 vertex;
    part.getVertex(index, vertex);
    vertex = transform(vertex);
    const btScalar distance = vertex.dot(equation) - equation[3] - margin;
    if (distance < 0.0) add(vertex, distance);
}

/// The filter over the locked part's stored vertices of type T, last to first, calling `test` with each vertex it
/// lets through; returns how many.
template <typename T, typename Test>
std::size_t filterVertices(const btGImpactMeshShapePart::TrimeshPrimitiveManager& mesh, int count,
                           const PlaneFilter& filter, const Test& test) {
    std::size_t passed = 0;
    const unsigned char* base = mesh.vertexbase;
    const std::ptrdiff_t stride = mesh.stride;
    for (int v = count; v--;) {
        const T* p = reinterpret_cast<const T*>(base + std::ptrdiff_t(v) * stride);
        if (filter.mayTouch(btScalar(p[0]), btScalar(p[1]), btScalar(p[2]))) {
            test(v);
            ++passed;
        }
    }
    return passed;
}

#if defined(__SSE2__) && !defined(BT_USE_DOUBLE_PRECISION)
/// filterVertices for packed float vertices (x, y, z, x, ...), four at a time: the same operations in the same order
/// in each lane, so the same decisions.
template <typename Test>
std::size_t filterPackedFloats(const float* vertices, int count, const PlaneFilter& filter, const Test& test) {
    std::size_t passed = 0;
    int v = count;
    for (; v % 4 != 0; --v) {  // the last few, one by one
        const float* p = vertices + 3 * std::ptrdiff_t(v - 1);
        if (filter.mayTouch(p[0], p[1], p[2])) {
            test(v - 1);
            ++passed;
        }
    }
    const __m128 n0 = _mm_set1_ps(filter.normal()[0]), n1 = _mm_set1_ps(filter.normal()[1]);
    const __m128 n2 = _mm_set1_ps(filter.normal()[2]), offset = _mm_set1_ps(filter.offset());
    const __m128 e0 = _mm_set1_ps(filter.error()[0]), e1 = _mm_set1_ps(filter.error()[1]);
    const __m128 e2 = _mm_set1_ps(filter.error()[2]), errorOffset = _mm_set1_ps(filter.errorOffset());
    const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    for (; v > 0; v -= 4) {
        const float* p = vertices + 3 * std::ptrdiff_t(v - 4);
        const __m128 m0 = _mm_loadu_ps(p), m1 = _mm_loadu_ps(p + 4), m2 = _mm_loadu_ps(p + 8);
        // m0 = x0 y0 z0 x1, m1 = y1 z1 x2 y2, m2 = z2 x3 y3 z3
        const __m128 a = _mm_shuffle_ps(m0, m1, _MM_SHUFFLE(1, 0, 3, 0));  // x0 x1 y1 z1
        const __m128 b = _mm_shuffle_ps(m1, m2, _MM_SHUFFLE(2, 1, 3, 2));  // x2 y2 x3 y3
        const __m128 x = _mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 1, 0));
        const __m128 y = _mm_shuffle_ps(_mm_shuffle_ps(m0, a, _MM_SHUFFLE(2, 2, 1, 1)), b, _MM_SHUFFLE(3, 1, 2, 0));
        const __m128 z = _mm_shuffle_ps(_mm_shuffle_ps(m0, a, _MM_SHUFFLE(3, 3, 2, 2)),
                                        _mm_shuffle_ps(m2, m2, _MM_SHUFFLE(3, 0, 3, 0)), _MM_SHUFFLE(1, 0, 2, 0));
        const __m128 distance =
            _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(n0, x), _mm_mul_ps(n1, y)), _mm_mul_ps(n2, z)), offset);
        const __m128 error = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(e0, _mm_and_ps(x, magnitude)),
                                                              _mm_mul_ps(e1, _mm_and_ps(y, magnitude))),
                                                   _mm_mul_ps(e2, _mm_and_ps(z, magnitude))),
                                        errorOffset);
        const int mask = _mm_movemask_ps(_mm_cmpngt_ps(distance, error));  // !(distance > error), as mayTouch
        for (int lane = 3; lane >= 0; --lane)
            if (mask & (1 << lane)) {
                test(v - 4 + lane);
                ++passed;
            }
    }
    return passed;
}
#endif

/// The filter over the locked part's vertices, as Bullet's get_vertex reads them (doubles as doubles, any other type
/// as floats).
template <typename Test>
std::size_t filterPart(const btGImpactMeshShapePart::TrimeshPrimitiveManager& mesh, int count,
                       const PlaneFilter& filter, const Test& test) {
    if (mesh.type == PHY_DOUBLE) return filterVertices<double>(mesh, count, filter, test);
#if defined(__SSE2__) && !defined(BT_USE_DOUBLE_PRECISION)
    if (mesh.stride == 3 * int(sizeof(float)))
        return filterPackedFloats(reinterpret_cast<const float*>(mesh.vertexbase), count, filter, test);
#endif
    return filterVertices<float>(mesh, count, filter, test);
}

}  // namespace

void planePartContacts(const btGImpactMeshShapePart& part, const btTransform& partTransform, const btVector4& equation,
                       btScalar planeMargin, const PlanePointSink& add, PlaneCounts& counts) {
    btAABB box;
    part.getAabb(partTransform, box.m_min, box.m_max);
    box.increment_margin(planeMargin);
    if (box.plane_classify(equation) != BT_CONST_COLLIDE_PLANE) return;
    part.lockChildShapes();
    const btScalar margin = part.getMargin() + planeMargin;
    const auto& mesh = *const_cast<btGImpactMeshShapePart&>(part).getTrimeshPrimitiveManager();
    const int vertices = std::max(part.getVertexCount(), 0);
    counts.vertices += static_cast<std::size_t>(vertices);
    const PlaneFilter filter(partTransform, mesh.m_scale, equation, margin);
    const auto test = [&](int v) { testVertex(part, v, partTransform, equation, margin, add); };
    counts.tested += filterPart(mesh, vertices, filter, test);
    part.unlockChildShapes();
}

}  // namespace cullide::bullet
