#include "ShapeGeometry.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btStridingMeshInterface.h>
#include <BulletCollision/CollisionShapes/btTriangleMeshShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cstring>

namespace cullide::bullet {
namespace {

const btGImpactMeshShape* asGImpactMesh(const btCollisionShape* shape) {
    if (shape == nullptr || shape->getShapeType() != GIMPACT_SHAPE_PROXYTYPE) return nullptr;
    const auto* g = static_cast<const btGImpactShapeInterface*>(shape);
    if (g->getGImpactShapeType() != CONST_GIMPACT_TRIMESH_SHAPE) return nullptr;
    return static_cast<const btGImpactMeshShape*>(g);
}

int gimpactVertexCount(const btGImpactMeshShape& mesh) {
    int n = 0;
    for (int p = 0; p < mesh.getMeshPartCount(); ++p) {
        const btGImpactMeshShapePart* part = mesh.getMeshPart(p);
        part->lockChildShapes();  // the vertex count is read from the striding mesh at lock time
        n += part->getVertexCount();
        part->unlockChildShapes();
    }
    return n;
}

/// One subpart of a striding mesh, locked for reading for the lifetime of the view.
struct SubpartView {
    const btStridingMeshInterface& mesh;
    int subpart;
    const unsigned char* vertexBase = nullptr;
    const unsigned char* indexBase = nullptr;
    int numVerts = 0, stride = 0, indexStride = 0, numFaces = 0;
    PHY_ScalarType type = PHY_FLOAT, indexType = PHY_INTEGER;

    SubpartView(const btStridingMeshInterface& m, int s) : mesh(m), subpart(s) {
        mesh.getLockedReadOnlyVertexIndexBase(&vertexBase, numVerts, type, stride, &indexBase, indexStride, numFaces,
                                              indexType, subpart);
    }
    ~SubpartView() { mesh.unLockReadOnlyVertexBase(subpart); }
    SubpartView(const SubpartView&) = delete;
    SubpartView& operator=(const SubpartView&) = delete;
};

int meshVertexCount(const btStridingMeshInterface& mesh) {
    int n = 0;
    for (int s = 0; s < mesh.getNumSubParts(); ++s) n += SubpartView(mesh, s).numVerts;
    return n;
}

/// 64-bit hash of raw bytes: four independent lanes of 8 bytes (the multiply chains overlap, ~4x the throughput
/// of one lane: the adapter hashes every mesh shape every step), folded together at the end. Detects deformation
/// with no help from the application beyond what Bullet itself needs (the vertex data).
#if defined(__GNUC__) && !defined(__clang__)
// GCC vectorizes the four lanes into SSE2, which has no 64-bit multiply and emulates it with shifts: 4x slower.
__attribute__((optimize("no-tree-vectorize")))
#endif
std::uint64_t hashBytes(std::uint64_t h, const unsigned char* data, std::size_t size) {
    constexpr std::uint64_t kPrime = 0x100000001b3ull;
    auto mix = [](std::uint64_t lane, std::uint64_t w) {
        lane = (lane ^ w) * kPrime;
        return lane ^ (lane >> 29);
    };
    std::uint64_t lane[4] = {h, h ^ 0x9e3779b97f4a7c15ull, h ^ 0xbf58476d1ce4e5b9ull, h ^ 0x94d049bb133111ebull};
    std::size_t i = 0;
    for (; i + 32 <= size; i += 32) {
        std::uint64_t w[4];
        std::memcpy(w, data + i, 32);
        for (int k = 0; k < 4; ++k) lane[k] = mix(lane[k], w[k]);
    }
    for (; i + 8 <= size; i += 8) {
        std::uint64_t w = 0;
        std::memcpy(&w, data + i, 8);
        lane[0] = mix(lane[0], w);
    }
    for (; i < size; ++i) lane[0] = (lane[0] ^ data[i]) * kPrime;
    std::uint64_t out = mix(mix(mix(lane[0], lane[1]), lane[2]), lane[3]);
    return mix(out, size);
}

/// Hash of `count` records of `bytes` bytes, `stride` apart: tightly packed arrays (the common case) in one pass;
/// padded ones (btVector3's unused fourth float, interleaved layouts) gathered in blocks first, padding left out.
std::uint64_t hashStrided(std::uint64_t h, const unsigned char* base, int count, int stride, std::size_t bytes) {
    if (count <= 0) return h;
    if (static_cast<std::size_t>(stride) == bytes) return hashBytes(h, base, static_cast<std::size_t>(count) * bytes);
    constexpr int kBlock = 1024;
    std::vector<unsigned char> block(static_cast<std::size_t>(kBlock) * bytes);
    for (int first = 0; first < count; first += kBlock) {
        const int n = std::min(kBlock, count - first);
        for (int i = 0; i < n; ++i)
            std::memcpy(block.data() + static_cast<std::size_t>(i) * bytes,
                        base + static_cast<std::ptrdiff_t>(first + i) * stride, bytes);
        h = hashBytes(h, block.data(), static_cast<std::size_t>(n) * bytes);
    }
    return h;
}

/// Hash of one subpart's vertex and index data of a striding mesh.
std::uint64_t hashSubpart(std::uint64_t h, const btStridingMeshInterface& mesh, int subpart) {
    const SubpartView v(mesh, subpart);
    const std::size_t vertexBytes = v.type == PHY_DOUBLE ? 3 * sizeof(double) : 3 * sizeof(float);
    const std::size_t indexBytes = v.indexType == PHY_SHORT ? 3 * sizeof(unsigned short)
                                   : v.indexType == PHY_UCHAR ? 3 : 3 * sizeof(unsigned int);
    h = hashStrided(h, v.vertexBase, v.numVerts, v.stride, vertexBytes);
    return hashStrided(h, v.indexBase, v.numFaces, v.indexStride, indexBytes);
}

}  // namespace

std::uint64_t sourceHashOf(const btCollisionShape* shape) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    if (const btGImpactMeshShape* mesh = asGImpactMesh(shape)) {
        for (int p = 0; p < mesh->getMeshPartCount(); ++p) {
            auto* part = const_cast<btGImpactMeshShapePart*>(mesh->getMeshPart(p));
            const auto* manager = part->getTrimeshPrimitiveManager();
            h = hashSubpart(h, *manager->m_meshInterface, manager->m_part);
        }
    } else if (geometryKindOf(shape) == GeometryKind::TriangleMesh) {
        const btStridingMeshInterface& striding = *static_cast<const btTriangleMeshShape*>(shape)->getMeshInterface();
        for (int s = 0; s < striding.getNumSubParts(); ++s) h = hashSubpart(h, striding, s);
    } else if (geometryKindOf(shape) == GeometryKind::ConvexHull) {
        const auto* hull = static_cast<const btConvexHullShape*>(shape);
        h = hashBytes(h, reinterpret_cast<const unsigned char*>(hull->getUnscaledPoints()),
                      static_cast<std::size_t>(hull->getNumPoints()) * sizeof(btVector3));
    }
    return h;
}

namespace {

void buildGImpact(const btGImpactMeshShape& mesh, ShapeTriangles& out) {
    for (int p = 0; p < mesh.getMeshPartCount(); ++p) {
        // The part is logically const; the primitive manager accessor is not.
        auto* part = const_cast<btGImpactMeshShapePart*>(mesh.getMeshPart(p));
        part->lockChildShapes();
        const auto base = static_cast<std::uint32_t>(out.vertices.size());
        const int vertexCount = part->getVertexCount();
        for (int v = 0; v < vertexCount; ++v) {
            btVector3 vertex;
            part->getVertex(v, vertex);
            out.vertices.push_back(vertex);
        }
        const btGImpactMeshShapePart::TrimeshPrimitiveManager* manager = part->getTrimeshPrimitiveManager();
        const int triangleCount = part->getNumChildShapes();
        for (int t = 0; t < triangleCount; ++t) {
            unsigned int i0 = 0, i1 = 0, i2 = 0;
            manager->get_indices(t, i0, i1, i2);
            out.triangles.push_back({base + i0, base + i1, base + i2});
            out.refs.push_back({p, t});
        }
        out.margin = std::max(out.margin, part->getMargin());
        part->unlockChildShapes();
    }
}

void buildTriangleMesh(const btStridingMeshInterface& mesh, ShapeTriangles& out) {
    const btVector3& scaling = mesh.getScaling();
    for (int s = 0; s < mesh.getNumSubParts(); ++s) {
        const SubpartView view(mesh, s);
        const unsigned char* vertexBase = view.vertexBase;
        const unsigned char* indexBase = view.indexBase;
        const int numVerts = view.numVerts, stride = view.stride, indexStride = view.indexStride;
        const int numFaces = view.numFaces;
        const PHY_ScalarType type = view.type, indexType = view.indexType;
        const auto base = static_cast<std::uint32_t>(out.vertices.size());
        // Same arithmetic as btBvhTriangleMeshShape::processAllTriangles, so the triangles are bit-identical.
        for (int v = 0; v < numVerts; ++v) {
            const unsigned char* p = vertexBase + static_cast<std::ptrdiff_t>(v) * stride;
            if (type == PHY_DOUBLE) {
                double c[3];
                std::memcpy(c, p, sizeof c);
                out.vertices.emplace_back(btScalar(c[0]) * scaling.getX(), btScalar(c[1]) * scaling.getY(),
                                          btScalar(c[2]) * scaling.getZ());
            } else {
                float c[3];
                std::memcpy(c, p, sizeof c);
                out.vertices.emplace_back(c[0] * scaling.getX(), c[1] * scaling.getY(), c[2] * scaling.getZ());
            }
        }
        for (int t = 0; t < numFaces; ++t) {
            const unsigned char* q = indexBase + static_cast<std::ptrdiff_t>(t) * indexStride;
            std::uint32_t idx[3] = {0, 0, 0};
            for (int j = 0; j < 3; ++j) {
                if (indexType == PHY_SHORT) {
                    unsigned short i = 0;
                    std::memcpy(&i, q + j * sizeof(unsigned short), sizeof i);
                    idx[j] = i;
                } else if (indexType == PHY_UCHAR) {
                    idx[j] = q[j];
                } else {
                    unsigned int i = 0;
                    std::memcpy(&i, q + j * sizeof(unsigned int), sizeof i);
                    idx[j] = i;
                }
            }
            out.triangles.push_back({base + idx[0], base + idx[1], base + idx[2]});
            out.refs.push_back({s, t});
        }
    }
}

void buildConvexHull(const btConvexHullShape& hull, ShapeTriangles& out) {
    const int n = hull.getNumPoints();
    btAlignedObjectArray<btVector3> points;
    points.resize(n);
    for (int i = 0; i < n; ++i) points[i] = hull.getScaledPoint(i);
    btConvexHullComputer computer;
    computer.compute(points[0].m_floats, static_cast<int>(sizeof(btVector3)), n, 0, 0);
    for (int v = 0; v < computer.vertices.size(); ++v) out.vertices.push_back(computer.vertices[v]);
    std::vector<std::uint32_t> polygon;
    for (int f = 0; f < computer.faces.size(); ++f) {
        const btConvexHullComputer::Edge* start = &computer.edges[computer.faces[f]];
        const btConvexHullComputer::Edge* e = start;
        polygon.clear();
        do {
            polygon.push_back(static_cast<std::uint32_t>(e->getSourceVertex()));
            e = e->getNextEdgeOfFace();
        } while (e != start && polygon.size() <= static_cast<std::size_t>(computer.vertices.size()));
        for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
            out.refs.push_back({0, static_cast<int>(out.triangles.size())});
            out.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
        }
    }
    out.margin = hull.getMargin();
}

}  // namespace

GeometryKind geometryKindOf(const btCollisionShape* shape) {
    if (shape == nullptr) return GeometryKind::None;
    switch (shape->getShapeType()) {
        case GIMPACT_SHAPE_PROXYTYPE:
            return asGImpactMesh(shape) != nullptr ? GeometryKind::GImpactMesh : GeometryKind::None;
        case TRIANGLE_MESH_SHAPE_PROXYTYPE:
            return GeometryKind::TriangleMesh;
        case CONVEX_HULL_SHAPE_PROXYTYPE:
            return GeometryKind::ConvexHull;
        default:
            return GeometryKind::None;
    }
}

std::shared_ptr<ShapeTriangles> buildShapeTriangles(const btCollisionShape* shape, std::uint64_t sourceHash) {
    const GeometryKind kind = geometryKindOf(shape);
    if (kind == GeometryKind::None) return nullptr;
    auto out = std::make_shared<ShapeTriangles>();
    out->kind = kind;
    out->shape = shape;
    out->scaling = shape->getLocalScaling();
    out->sourceHash = sourceHash;
    switch (kind) {
        case GeometryKind::GImpactMesh: {
            const btGImpactMeshShape& mesh = *asGImpactMesh(shape);
            out->sourceCount = gimpactVertexCount(mesh);
            buildGImpact(mesh, *out);
            break;
        }
        case GeometryKind::TriangleMesh: {
            const auto* mesh = static_cast<const btTriangleMeshShape*>(shape);
            out->sourceCount = meshVertexCount(*mesh->getMeshInterface());
            buildTriangleMesh(*mesh->getMeshInterface(), *out);
            out->margin = shape->getMargin();
            break;
        }
        case GeometryKind::ConvexHull: {
            const auto* hull = static_cast<const btConvexHullShape*>(shape);
            out->sourceCount = hull->getNumPoints();
            if (out->sourceCount > 0) buildConvexHull(*hull, *out);
            break;
        }
        case GeometryKind::None:
            break;
    }
    if (out->triangles.empty()) return nullptr;
    return out;
}

bool stillMatches(const ShapeTriangles& geometry, const btCollisionShape* shape, std::uint64_t sourceHash) {
    if (geometry.shape != shape || geometryKindOf(shape) != geometry.kind) return false;
    if (!(shape->getLocalScaling() == geometry.scaling)) return false;
    bool sameSize = false;
    switch (geometry.kind) {
        case GeometryKind::GImpactMesh:
            sameSize = gimpactVertexCount(*asGImpactMesh(shape)) == geometry.sourceCount;
            break;
        case GeometryKind::TriangleMesh:
            sameSize = meshVertexCount(*static_cast<const btTriangleMeshShape*>(shape)->getMeshInterface()) ==
                       geometry.sourceCount;
            break;
        case GeometryKind::ConvexHull:
            sameSize = static_cast<const btConvexHullShape*>(shape)->getNumPoints() == geometry.sourceCount;
            break;
        case GeometryKind::None:
            return false;
    }
    // Deformation in place (same counts, new vertex data) is caught by the content hash.
    return sameSize && sourceHash == geometry.sourceHash;
}

btScalar triangleMarginOf(const btCollisionShape* shape) {
    if (const btGImpactMeshShape* mesh = asGImpactMesh(shape)) {
        btScalar m = 0;
        for (int p = 0; p < mesh->getMeshPartCount(); ++p) m = std::max(m, mesh->getMeshPart(p)->getMargin());
        return m;
    }
    return shape != nullptr ? shape->getMargin() : btScalar(0);
}

}  // namespace cullide::bullet
