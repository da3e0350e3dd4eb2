#include "broadphase/ShapeGeometry.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btStridingMeshInterface.h>
#include <BulletCollision/CollisionShapes/btScaledBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btTriangleMeshShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cmath>
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

const btTriangleMeshShape* triangleMeshOf(const btCollisionShape* shape) {
    if (shape == nullptr) return nullptr;
    if (shape->getShapeType() == TRIANGLE_MESH_SHAPE_PROXYTYPE) return static_cast<const btTriangleMeshShape*>(shape);
    if (shape->getShapeType() == SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE)
        return const_cast<btScaledBvhTriangleMeshShape*>(static_cast<const btScaledBvhTriangleMeshShape*>(shape))
            ->getChildShape();  // logically const; Bullet's accessor is not
    return nullptr;
}

std::uint64_t sourceHashOf(const btCollisionShape* shape) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    if (const btGImpactMeshShape* mesh = asGImpactMesh(shape)) {
        for (int p = 0; p < mesh->getMeshPartCount(); ++p) {
            auto* part = const_cast<btGImpactMeshShapePart*>(mesh->getMeshPart(p));
            const auto* manager = part->getTrimeshPrimitiveManager();
            h = hashSubpart(h, *manager->m_meshInterface, manager->m_part);
        }
    } else if (geometryKindOf(shape) == GeometryKind::TriangleMesh) {
        const btStridingMeshInterface& striding = *triangleMeshOf(shape)->getMeshInterface();
        for (int s = 0; s < striding.getNumSubParts(); ++s) h = hashSubpart(h, striding, s);
        // A scaled wrapper's child can be rescaled on its own (its mesh interface's scaling).
        h = hashBytes(h, reinterpret_cast<const unsigned char*>(striding.getScaling().m_floats), 3 * sizeof(btScalar));
    } else if (geometryKindOf(shape) == GeometryKind::ConvexHull) {
        const auto* hull = static_cast<const btConvexHullShape*>(shape);
        h = hashBytes(h, reinterpret_cast<const unsigned char*>(hull->getUnscaledPoints()),
                      static_cast<std::size_t>(hull->getNumPoints()) * sizeof(btVector3));
    } else if (geometryKindOf(shape) == GeometryKind::Compound) {
        // Children, their placement and what each is built from: updateChildTransform, added or removed children,
        // rescaled or edited children all change it.
        const auto* compound = static_cast<const btCompoundShape*>(shape);
        for (int i = 0; i < compound->getNumChildShapes(); ++i) {
            const btCollisionShape* child = compound->getChildShape(i);
            btVector3 record[6];
            const btTransform& t = compound->getChildTransform(i);
            for (int r = 0; r < 3; ++r) record[r] = t.getBasis()[r];
            record[3] = t.getOrigin();
            child->getAabb(btTransform::getIdentity(), record[4], record[5]);
            const std::uintptr_t id = reinterpret_cast<std::uintptr_t>(child);
            h = hashBytes(h, reinterpret_cast<const unsigned char*>(&id), sizeof id);
            for (const btVector3& v : record)
                h = hashBytes(h, reinterpret_cast<const unsigned char*>(v.m_floats), 3 * sizeof(btScalar));
            h = hashBytes(h, reinterpret_cast<const unsigned char*>(child->getLocalScaling().m_floats),
                          3 * sizeof(btScalar));
            h ^= sourceHashOf(child) * 0x9e3779b97f4a7c15ull;
        }
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

/// Whether a coordinate is one the culler's geometry can take: finite and within 1e15 (btConvexHullComputer maps
/// points to integers and crashes on a NaN; beyond that the culler's exact arithmetic has no headroom).
bool usableCoordinate(btScalar c) { return std::isfinite(double(c)) && std::fabs(double(c)) <= 1e15; }

/// The hull's triangles (its points' convex hull, as Bullet's btConvexHullComputer builds it); false, and `out`
/// unchanged, when a scaled point has an unusable coordinate: such a hull gets no triangles, so its pairs are not
/// culled and run Bullet's own algorithm.
bool buildConvexHull(const btConvexHullShape& hull, ShapeTriangles& out) {
    const int n = hull.getNumPoints();
    btAlignedObjectArray<btVector3> points;
    points.resize(n);
    for (int i = 0; i < n; ++i) {
        points[i] = hull.getScaledPoint(i);
        for (int a = 0; a < 3; ++a)
            if (!usableCoordinate(points[i][a])) return false;
    }
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
    return true;
}

/// Appends `part` (triangles in its own frame) to `out`, placed by `t`.
void appendPlaced(const ShapeTriangles& part, const btTransform& t, ShapeTriangles& out) {
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (const btVector3& v : part.vertices) out.vertices.push_back(t * v);
    for (const TriangleIndices& tri : part.triangles) {
        out.refs.push_back({0, static_cast<int>(out.triangles.size())});
        out.triangles.push_back({base + tri[0], base + tri[1], base + tri[2]});
    }
}

/// The 12 triangles of a box [mn, mx] placed by `t`.
void appendBox(const btVector3& mn, const btVector3& mx, const btTransform& t, ShapeTriangles& out) {
    ShapeTriangles box;
    for (int i = 0; i < 8; ++i)
        box.vertices.emplace_back(i & 1 ? mx.x() : mn.x(), i & 2 ? mx.y() : mn.y(), i & 4 ? mx.z() : mn.z());
    box.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    appendPlaced(box, t, out);
}

/// Children of a compound into `out` (compound frame); false when a child has no convex description.
bool buildCompound(const btCompoundShape& compound, const btTransform& placement, int depth, ShapeTriangles& out) {
    if (depth > 32) return false;  // not a shape Bullet itself could traverse sensibly
    for (int i = 0; i < compound.getNumChildShapes(); ++i) {
        const btCollisionShape* child = compound.getChildShape(i);
        const btTransform t = placement * compound.getChildTransform(i);
        if (child->getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
            if (!buildCompound(*static_cast<const btCompoundShape*>(child), t, depth + 1, out)) return false;
        } else if (child->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE &&
                   static_cast<const btConvexHullShape*>(child)->getNumPoints() > 0) {
            ShapeTriangles hull;
            if (!buildConvexHull(*static_cast<const btConvexHullShape*>(child), hull)) return false;
            appendPlaced(hull, t, out);
        } else if (child->isConvex()) {
            btVector3 mn, mx;  // the child's local box, its collision margin included
            child->getAabb(btTransform::getIdentity(), mn, mx);
            for (int a = 0; a < 3; ++a)
                if (!usableCoordinate(mn[a]) || !usableCoordinate(mx[a])) return false;
            appendBox(mn, mx, t, out);
        } else {
            return false;  // a concave child (mesh, plane, heightfield): the compound stays a box proxy
        }
        out.margin = std::max(out.margin, child->getMargin());
    }
    return true;
}

}  // namespace

GeometryKind geometryKindOf(const btCollisionShape* shape) {
    if (shape == nullptr) return GeometryKind::None;
    switch (shape->getShapeType()) {
        case GIMPACT_SHAPE_PROXYTYPE:
            return asGImpactMesh(shape) != nullptr ? GeometryKind::GImpactMesh : GeometryKind::None;
        case TRIANGLE_MESH_SHAPE_PROXYTYPE:
            return GeometryKind::TriangleMesh;
        case SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE:
            return triangleMeshOf(shape) != nullptr ? GeometryKind::TriangleMesh : GeometryKind::None;
        case CONVEX_HULL_SHAPE_PROXYTYPE:
            return GeometryKind::ConvexHull;
        case COMPOUND_SHAPE_PROXYTYPE:
            return GeometryKind::Compound;
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
            const btTriangleMeshShape* mesh = triangleMeshOf(shape);
            out->sourceCount = meshVertexCount(*mesh->getMeshInterface());
            buildTriangleMesh(*mesh->getMeshInterface(), *out);
            if (mesh != shape) {
                // btScaledBvhTriangleMeshShape: its callback multiplies the child's triangles by its own scaling.
                const btVector3 scaling = shape->getLocalScaling();
                for (btVector3& v : out->vertices) v = v * scaling;
            }
            out->margin = shape->getMargin();  // the wrapper's own margin is what the concave algorithms use
            break;
        }
        case GeometryKind::ConvexHull: {
            const auto* hull = static_cast<const btConvexHullShape*>(shape);
            out->sourceCount = hull->getNumPoints();
            if (out->sourceCount > 0 && !buildConvexHull(*hull, *out)) return nullptr;
            break;
        }
        case GeometryKind::Compound: {
            const auto* compound = static_cast<const btCompoundShape*>(shape);
            out->sourceCount = compound->getNumChildShapes();
            if (!buildCompound(*compound, btTransform::getIdentity(), 0, *out)) return nullptr;
            break;
        }
        case GeometryKind::None:
            break;
    }
    if (out->triangles.empty()) return nullptr;
    out->local.triangles = out->triangles;
    out->local.vertices.reserve(out->vertices.size());
    for (const btVector3& v : out->vertices)
        out->local.vertices.emplace_back(double(v.x()), double(v.y()), double(v.z()));
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
            sameSize = meshVertexCount(*triangleMeshOf(shape)->getMeshInterface()) == geometry.sourceCount;
            break;
        case GeometryKind::ConvexHull:
            sameSize = static_cast<const btConvexHullShape*>(shape)->getNumPoints() == geometry.sourceCount;
            break;
        case GeometryKind::Compound:
            sameSize = static_cast<const btCompoundShape*>(shape)->getNumChildShapes() == geometry.sourceCount;
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
    if (shape != nullptr && shape->getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
        const auto* compound = static_cast<const btCompoundShape*>(shape);
        btScalar m = 0;
        for (int i = 0; i < compound->getNumChildShapes(); ++i)
            m = std::max(m, triangleMarginOf(compound->getChildShape(i)));
        return m;
    }
    return shape != nullptr ? shape->getMargin() : btScalar(0);
}

}  // namespace cullide::bullet
