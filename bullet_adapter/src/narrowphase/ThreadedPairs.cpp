#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btBoxBoxCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btCompoundCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCompoundCompoundCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btHashedSimplePairCache.h>
#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexConvexAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexPlaneCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionDispatch/btSphereBoxCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSphereSphereCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSphereTriangleCollisionAlgorithm.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConeShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btConvexPointCloudShape.h>
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btMultiSphereShape.h>
#include <BulletCollision/CollisionShapes/btScaledBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btConvexTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btTetrahedronShape.h>
#include <BulletCollision/CollisionShapes/btTriangleMesh.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <LinearMath/btAabbUtil2.h>
#include <LinearMath/btIDebugDraw.h>
#include <LinearMath/btQuickprof.h>


namespace cullide::bullet {
namespace {

template <typename... T>
bool isOneOf(const std::type_info& type) {
    return ((type == typeid(T)) || ...);
}

/// Bullet's own vertex arrays, whose triangle queries read the arrays only (an application's btStridingMeshInterface
/// may lock).
bool bulletMeshInterface(const btStridingMeshInterface* mesh) {
    return mesh != nullptr && isOneOf<btTriangleIndexVertexArray, btTriangleMesh>(typeid(*mesh));
}

/// Bullet's convex shape classes: support functions that read the shape only. The proxy type narrows the class down
/// first (a type_info comparison of different classes may compare their names).
bool bulletConvex(const btCollisionShape& shape) {
    const std::type_info& type = typeid(shape);
    switch (shape.getShapeType()) {
        case BOX_SHAPE_PROXYTYPE:
            return type == typeid(btBoxShape);
        case SPHERE_SHAPE_PROXYTYPE:
            return type == typeid(btSphereShape);
        case CAPSULE_SHAPE_PROXYTYPE:
            return isOneOf<btCapsuleShape, btCapsuleShapeX, btCapsuleShapeZ>(type);
        case CYLINDER_SHAPE_PROXYTYPE:
            return isOneOf<btCylinderShape, btCylinderShapeX, btCylinderShapeZ>(type);
        case CONE_SHAPE_PROXYTYPE:
            return isOneOf<btConeShape, btConeShapeX, btConeShapeZ>(type);
        case CONVEX_HULL_SHAPE_PROXYTYPE:
            return type == typeid(btConvexHullShape);
        case CONVEX_POINT_CLOUD_SHAPE_PROXYTYPE:
            return type == typeid(btConvexPointCloudShape);
        case MULTI_SPHERE_SHAPE_PROXYTYPE:
            return type == typeid(btMultiSphereShape);
        case TETRAHEDRAL_SHAPE_PROXYTYPE:
            return type == typeid(btBU_Simplex1to4);
        case TRIANGLE_SHAPE_PROXYTYPE:
            return type == typeid(btTriangleShape);
        case CONVEX_TRIANGLEMESH_SHAPE_PROXYTYPE:  // its support function walks the mesh's triangles
            return type == typeid(btConvexTriangleMeshShape) &&
                   bulletMeshInterface(static_cast<const btConvexTriangleMeshShape&>(shape).getMeshInterface());
        default:
            return false;
    }
}

/// Bullet's concave shapes whose triangle queries read the shape only: BVH meshes over Bullet's own vertex arrays
/// (an application's btStridingMeshInterface may lock), scaled, and heightfields.
bool bulletConcave(const btCollisionShape& shape) {
    const std::type_info& type = typeid(shape);
    if (type == typeid(btScaledBvhTriangleMeshShape))
        return bulletConcave(*static_cast<const btScaledBvhTriangleMeshShape&>(shape).getChildShape());
    if (type == typeid(btBvhTriangleMeshShape))
        return bulletMeshInterface(static_cast<const btBvhTriangleMeshShape&>(shape).getMeshInterface());
    return type == typeid(btHeightfieldTerrainShape);
}

/// Bullet's convex-convex creation function with a GJK-EPA solver (btMinkowskiPenetrationDepthSolver writes a
/// static table of directions).
bool bulletConvexFunc(const btCollisionAlgorithmCreateFunc* f) {
    if (f == nullptr || typeid(*f) != typeid(btConvexConvexAlgorithm::CreateFunc)) return false;
    const btConvexPenetrationDepthSolver* solver = static_cast<const btConvexConvexAlgorithm::CreateFunc*>(f)->m_pdSolver;
    return solver != nullptr && typeid(*solver) == typeid(btGjkEpaPenetrationDepthSolver);
}

/// The profile hooks at load time (Bullet's defaults unless the application installs its own).
btEnterProfileZoneFunc* const g_defaultEnterProfile = btGetCurrentEnterProfileZoneFunc();
btLeaveProfileZoneFunc* const g_defaultLeaveProfile = btGetCurrentLeaveProfileZoneFunc();

thread_local bool t_onPairThread = false;

/// btCompoundCollisionAlgorithm's protected state, read through pointers to its members (formed in a derived class,
/// as the language allows): which object is the compound, the children's algorithms and the revision they are for.
struct CompoundAlgorithmState final : btCompoundCollisionAlgorithm {
    CompoundAlgorithmState() = delete;
    static bool swapped(const btCompoundCollisionAlgorithm& a) { return a.*(&CompoundAlgorithmState::m_isSwapped); }
    static int revision(const btCompoundCollisionAlgorithm& a) {
        return a.*(&CompoundAlgorithmState::m_compoundShapeRevision);
    }
    static int childCount(const btCompoundCollisionAlgorithm& a) {
        return (a.*(&CompoundAlgorithmState::m_childCollisionAlgorithms)).size();
    }
};

/// btCompoundCompoundCollisionAlgorithm's private state: its cache of child pairs (each with its algorithm) and the
/// revisions of the two compounds it was made for. Bullet has no accessor for them; pointers to them are named in an
/// explicit instantiation, where the language does not check access ([temp.explicit]), and handed out by a friend.
template <typename Tag, typename Tag::Type Member>
struct ExposedMember {
    friend typename Tag::Type memberPointer(Tag) { return Member; }
};
struct ChildPairCache {
    using Type = btHashedSimplePairCache* btCompoundCompoundCollisionAlgorithm::*;
    friend Type memberPointer(ChildPairCache);
};
struct Revision0 {
    using Type = int btCompoundCompoundCollisionAlgorithm::*;
    friend Type memberPointer(Revision0);
};
struct Revision1 {
    using Type = int btCompoundCompoundCollisionAlgorithm::*;
    friend Type memberPointer(Revision1);
};
template struct ExposedMember<ChildPairCache, &btCompoundCompoundCollisionAlgorithm::m_childCollisionAlgorithmCache>;
template struct ExposedMember<Revision0, &btCompoundCompoundCollisionAlgorithm::m_compoundShapeRevision0>;
template struct ExposedMember<Revision1, &btCompoundCompoundCollisionAlgorithm::m_compoundShapeRevision1>;

/// The world boxes of a compound's children as Bullet's compound algorithms compute them (child shape's getAabb at
/// the object's transform times the child's), for compounds of at most kMaxChildren children, all Bullet's convex
/// shapes; `extent` grows to the largest coordinate seen.
struct ChildBoxes {
    static constexpr int kMaxChildren = 16;
    btVector3 min[kMaxChildren], max[kMaxChildren];
    int count = 0;

    bool compute(const btCompoundShape& compound, const btTransform& transform, btScalar& extent) {
        count = compound.getNumChildShapes();
        if (count > kMaxChildren) return false;
        for (int i = 0; i < count; ++i) {
            const btCollisionShape& child = *compound.getChildShape(i);
            if (!bulletConvex(child)) return false;
            child.getAabb(transform * compound.getChildTransform(i), min[i], max[i]);
            extent = btMax(extent, largestMagnitude(min[i], max[i]));
        }
        return true;
    }
    static btScalar largestMagnitude(const btVector3& mn, const btVector3& mx) {
        btVector3 m = mn.absolute();
        m.setMax(mx.absolute());
        return btMax(m.x(), btMax(m.y(), m.z()));
    }
};

/// A few ulps of coordinates up to `extent`: how far a box computed in another build may be rounded differently.
btScalar roundingSlack(btScalar extent) { return btScalar(16) * SIMD_EPSILON * (btScalar(1) + extent); }

/// Whether two boxes overlap as TestAabbAgainstAabb2 decides, told apart from a decision that rounding the first box
/// by up to `slack` could turn: 1 overlapping, 0 apart, -1 too close to tell.
int clearOverlap(const btVector3& min0, const btVector3& max0, const btVector3& min1, const btVector3& max1,
                 btScalar slack) {
    const btVector3 s(slack, slack, slack);
    if (!TestAabbAgainstAabb2(min0 - s, max0 + s, min1, max1)) return 0;
    if (TestAabbAgainstAabb2(min0 + s, max0 - s, min1, max1)) return 1;
    return -1;
}

/// A shape whose box a compound algorithm reads on a worker: one of Bullet's convex or concave shapes, or a plane.
bool bulletShape(const btCollisionShape& shape) {
    return bulletConvex(shape) || bulletConcave(shape) || typeid(shape) == typeid(btStaticPlaneShape);
}

}  // namespace

AlgorithmKind algorithmKindOf(const std::type_info& algorithmClass) {
    // The most frequent first: each comparison with another class may compare names.
    if (algorithmClass == typeid(btConvexConvexAlgorithm)) return AlgorithmKind::ConvexConvex;
    if (algorithmClass == typeid(btBoxBoxCollisionAlgorithm)) return AlgorithmKind::Convex;
    if (algorithmClass == typeid(btConvexConcaveCollisionAlgorithm)) return AlgorithmKind::ConvexConcave;
    if (isOneOf<btCompoundCollisionAlgorithm, btCompoundCompoundCollisionAlgorithm>(algorithmClass))
        return AlgorithmKind::Compound;
    if (isOneOf<btSphereSphereCollisionAlgorithm, btSphereBoxCollisionAlgorithm, btSphereTriangleCollisionAlgorithm,
                btConvexPlaneCollisionAlgorithm>(algorithmClass))
        return AlgorithmKind::Convex;
    return AlgorithmKind::Other;
}

namespace {

/// Whether a single-compound algorithm (or the one a compound-compound algorithm derives from) holds no child
/// algorithm, and so no manifold.
bool holdsNoChild(const btCompoundCollisionAlgorithm& compound) {
    for (int i = 0; i < CompoundAlgorithmState::childCount(compound); ++i)
        if (compound.getChildAlgorithm(i) != nullptr) return false;
    return true;
}

}  // namespace

bool freesNoManifoldWhenApart(const btCollisionAlgorithm& algorithm) {
    const std::type_info& type = typeid(algorithm);
    switch (algorithmKindOf(type)) {
        case AlgorithmKind::Convex:
        case AlgorithmKind::ConvexConvex:
        case AlgorithmKind::ConvexConcave:
            return true;
        case AlgorithmKind::Compound:
            if (type == typeid(btCompoundCollisionAlgorithm))
                return holdsNoChild(static_cast<const btCompoundCollisionAlgorithm&>(algorithm));
            // Its own child pairs, and those of the single-compound algorithm it derives from, which it runs instead
            // when either compound has no box tree (btCompoundShape(false)): both must hold none.
            return holdsNoChild(static_cast<const btCompoundCollisionAlgorithm&>(algorithm)) &&
                   (static_cast<const btCompoundCompoundCollisionAlgorithm&>(algorithm).*
                    memberPointer(ChildPairCache{}))->getOverlappingPairArray().size() == 0;
        case AlgorithmKind::Other:
            break;
    }
    return false;
}

bool worthHandingOff(AlgorithmKind kind) {
    return kind == AlgorithmKind::ConvexConvex || kind == AlgorithmKind::ConvexConcave ||
           kind == AlgorithmKind::Compound;
}

std::size_t typicalCost(AlgorithmKind kind) {
    switch (kind) {
        case AlgorithmKind::Convex:
            return 1;
        case AlgorithmKind::ConvexConvex:
            return 4;
        case AlgorithmKind::ConvexConcave:
            return 16;
        case AlgorithmKind::Compound:
            return 4;
        case AlgorithmKind::Other:
            break;
    }
    return 0;
}

bool threadableAlgorithm(AlgorithmKind kind, const btCollisionShape& shape0, const btCollisionShape& shape1,
                         const btCollisionAlgorithmCreateFunc* pairFunc,
                         const btCollisionAlgorithmCreateFunc* triangleFunc) {
    const auto convexOrPlane = [](const btCollisionShape& s) {
        return bulletConvex(s) || typeid(s) == typeid(btStaticPlaneShape);
    };
    switch (kind) {
        case AlgorithmKind::Convex:
            return convexOrPlane(shape0) && convexOrPlane(shape1);
        case AlgorithmKind::ConvexConvex:
            return bulletConvex(shape0) && bulletConvex(shape1) && bulletConvexFunc(pairFunc);
        case AlgorithmKind::ConvexConcave: {
            const bool convexFirst = bulletConvex(shape0);
            const btCollisionShape& convex = convexFirst ? shape0 : shape1;
            const btCollisionShape& concave = convexFirst ? shape1 : shape0;
            return bulletConcave(concave) && convexTriangleThreadable(convex, triangleFunc);
        }
        case AlgorithmKind::Compound:  // compoundMayThread
        case AlgorithmKind::Other:
            break;
    }
    return false;
}

bool convexTriangleThreadable(const btCollisionShape& convex, const btCollisionAlgorithmCreateFunc* triangleFunc) {
    if (!bulletConvex(convex)) return false;
    return bulletConvexFunc(triangleFunc) ||
           (triangleFunc != nullptr && typeid(*triangleFunc) == typeid(btSphereTriangleCollisionAlgorithm::CreateFunc));
}

namespace {

/// Pairs btConvexConvexAlgorithm collides in closed form, without GJK (capsule-capsule, capsule-sphere; unless
/// Bullet was built with BT_DISABLE_CAPSULE_CAPSULE_COLLIDER, where they cost a GJK run but stay correct): about a
/// box-box pair's cost, less than handing them to another thread.
bool closedFormConvexPair(int type0, int type1) {
    const auto capsuleOrSphere = [](int t) { return t == CAPSULE_SHAPE_PROXYTYPE || t == SPHERE_SHAPE_PROXYTYPE; };
    return capsuleOrSphere(type0) && capsuleOrSphere(type1) &&
           (type0 == CAPSULE_SHAPE_PROXYTYPE || type1 == CAPSULE_SHAPE_PROXYTYPE);
}

/// threadableKind for a non-compound algorithm on two shapes (the algorithm's first, then its second).
AlgorithmKind threadableOnShapes(AlgorithmKind kind, btCollisionAlgorithm& algorithm, const btCollisionShape& shape0,
                                 const btCollisionShape& shape1, const CreateFuncTable& funcs,
                                 btManifoldArray& scratch) {
    const int t0 = shape0.getShapeType(), t1 = shape1.getShapeType();
    const int convexType = shape0.isConvex() ? t0 : t1;
    if (!threadableAlgorithm(kind, shape0, shape1, funcs[t0][t1], funcs[convexType][TRIANGLE_SHAPE_PROXYTYPE]))
        return AlgorithmKind::Other;
    if (kind != AlgorithmKind::ConvexConvex) return kind;
    if (closedFormConvexPair(t0, t1)) return AlgorithmKind::Convex;
    scratch.resize(0);  // btConvexConvexAlgorithm makes its manifold on its first run
    algorithm.getAllContactManifolds(scratch);
    return scratch.size() > 0 ? kind : AlgorithmKind::Other;
}

}  // namespace

AlgorithmKind threadableKind(btCollisionAlgorithm& algorithm, const btCollisionObject& object0,
                             const btCollisionObject& object1, const CreateFuncTable& funcs,
                             btManifoldArray& scratch) {
    const AlgorithmKind kind = algorithmKindOf(typeid(algorithm));
    if (kind == AlgorithmKind::Other) return kind;
    if (kind != AlgorithmKind::Compound)
        return threadableOnShapes(kind, algorithm, *object0.getCollisionShape(), *object1.getCollisionShape(), funcs,
                                  scratch);
    const auto child = [&](btCollisionAlgorithm& a, const btCollisionShape& childShape,
                           const btCollisionShape& otherShape) {
        const AlgorithmKind k = algorithmKindOf(typeid(a));
        return k != AlgorithmKind::Other && k != AlgorithmKind::Compound &&
               threadableOnShapes(k, a, childShape, otherShape, funcs, scratch) != AlgorithmKind::Other;
    };
    const bool mayThread = typeid(algorithm) == typeid(btCompoundCollisionAlgorithm)
                               ? compoundMayThread(algorithm, object0, object1, child)
                               : compoundPairMayThread(algorithm, object0, object1, child);
    return mayThread ? kind : AlgorithmKind::Other;
}

bool compoundMayThread(btCollisionAlgorithm& algorithm, const btCollisionObject& object0,
                       const btCollisionObject& object1, const ChildThreadable& childThreadable) {
    if (typeid(algorithm) != typeid(btCompoundCollisionAlgorithm) || gCompoundChildShapePairCallback != nullptr)
        return false;
    const auto& compoundAlgorithm = static_cast<const btCompoundCollisionAlgorithm&>(algorithm);
    const bool swapped = CompoundAlgorithmState::swapped(compoundAlgorithm);
    const btCollisionObject& compoundObject = swapped ? object1 : object0;
    const btCollisionObject& otherObject = swapped ? object0 : object1;
    const btCollisionShape& shape = *compoundObject.getCollisionShape();
    const btCollisionShape& otherShape = *otherObject.getCollisionShape();
    if (typeid(shape) != typeid(btCompoundShape) || !bulletShape(otherShape)) return false;
    const auto& compound = static_cast<const btCompoundShape&>(shape);
    if (CompoundAlgorithmState::revision(compoundAlgorithm) != compound.getUpdateRevision() ||
        CompoundAlgorithmState::childCount(compoundAlgorithm) != compound.getNumChildShapes())
        return false;
    bool worthIt = false;
    for (int i = 0; i < compound.getNumChildShapes() && !worthIt; ++i) {
        const btCollisionAlgorithm* child = compoundAlgorithm.getChildAlgorithm(i);
        worthIt = child != nullptr && worthHandingOff(algorithmKindOf(typeid(*child)));
    }
    if (!worthIt) return false;
    btVector3 otherMin, otherMax;
    otherShape.getAabb(otherObject.getWorldTransform(), otherMin, otherMax);
    btScalar extent = ChildBoxes::largestMagnitude(otherMin, otherMax);
    ChildBoxes boxes;
    if (!boxes.compute(compound, compoundObject.getWorldTransform(), extent)) return false;
    const btScalar slack = roundingSlack(extent);
    for (int i = 0; i < boxes.count; ++i) {
        btCollisionAlgorithm* const child = compoundAlgorithm.getChildAlgorithm(i);
        const int overlap = clearOverlap(boxes.min[i], boxes.max[i], otherMin, otherMax, slack);
        if (overlap != (child != nullptr ? 1 : 0)) return false;  // made, freed, or too close to tell
        if (child != nullptr && !childThreadable(*child, *compound.getChildShape(i), otherShape)) return false;
    }
    return true;
}

bool compoundPairMayThread(btCollisionAlgorithm& algorithm, const btCollisionObject& object0,
                           const btCollisionObject& object1, const ChildThreadable& childThreadable) {
    if (typeid(algorithm) != typeid(btCompoundCompoundCollisionAlgorithm) ||
        gCompoundCompoundChildShapePairCallback != nullptr)
        return false;
    const btCollisionShape& shape0 = *object0.getCollisionShape();
    const btCollisionShape& shape1 = *object1.getCollisionShape();
    if (typeid(shape0) != typeid(btCompoundShape) || typeid(shape1) != typeid(btCompoundShape)) return false;
    const auto& compound0 = static_cast<const btCompoundShape&>(shape0);
    const auto& compound1 = static_cast<const btCompoundShape&>(shape1);
    // Without both trees Bullet runs the single-compound algorithm, with compound children.
    if (compound0.getDynamicAabbTree() == nullptr || compound1.getDynamicAabbTree() == nullptr) return false;
    const auto& pairAlgorithm = static_cast<const btCompoundCompoundCollisionAlgorithm&>(algorithm);
    if (pairAlgorithm.*memberPointer(Revision0{}) != compound0.getUpdateRevision() ||
        pairAlgorithm.*memberPointer(Revision1{}) != compound1.getUpdateRevision())
        return false;
    const btSimplePairArray& cached = (pairAlgorithm.*memberPointer(ChildPairCache{}))->getOverlappingPairArray();
    bool worthIt = false;
    for (int k = 0; k < cached.size() && !worthIt; ++k) {
        const auto* child = static_cast<const btCollisionAlgorithm*>(cached[k].m_userPointer);
        worthIt = child != nullptr && worthHandingOff(algorithmKindOf(typeid(*child)));
    }
    if (!worthIt) return false;
    btScalar extent = 0;
    ChildBoxes boxes0, boxes1;
    if (!boxes0.compute(compound0, object0.getWorldTransform(), extent) ||
        !boxes1.compute(compound1, object1.getWorldTransform(), extent))
        return false;
    const btScalar slack = roundingSlack(extent);
    int overlapping = 0;
    for (int i = 0; i < boxes0.count; ++i)
        for (int j = 0; j < boxes1.count; ++j) {
            const int overlap = clearOverlap(boxes0.min[i], boxes0.max[i], boxes1.min[j], boxes1.max[j], slack);
            if (overlap < 0) return false;
            overlapping += overlap;
        }
    // Every child pair the cache holds overlaps, and there are as many as overlap: the cache holds exactly the
    // overlapping child pairs, so none is made or freed.
    if (cached.size() != overlapping) return false;
    for (int k = 0; k < cached.size(); ++k) {
        const btSimplePair& p = cached[k];
        if (p.m_userPointer == nullptr || p.m_indexA < 0 || p.m_indexA >= boxes0.count || p.m_indexB < 0 ||
            p.m_indexB >= boxes1.count)
            return false;
        const int i = p.m_indexA, j = p.m_indexB;
        if (clearOverlap(boxes0.min[i], boxes0.max[i], boxes1.min[j], boxes1.max[j], slack) != 1) return false;
        if (!childThreadable(*static_cast<btCollisionAlgorithm*>(p.m_userPointer), *compound0.getChildShape(i),
                             *compound1.getChildShape(j)))
            return false;
    }
    return true;
}

bool dispatchMayThread(const btDispatcherInfo& info) {
    if (info.m_dispatchFunc != btDispatcherInfo::DISPATCH_DISCRETE) return false;
    if (gContactStartedCallback != nullptr || gContactEndedCallback != nullptr ||
        gContactProcessedCallback != nullptr || gContactDestroyedCallback != nullptr)
        return false;
    if (gCalculateCombinedRestitutionCallback != &btManifoldResult::calculateCombinedRestitution ||
        gCalculateCombinedFrictionCallback != &btManifoldResult::calculateCombinedFriction ||
        gCalculateCombinedRollingFrictionCallback != &btManifoldResult::calculateCombinedRollingFriction ||
        gCalculateCombinedSpinningFrictionCallback != &btManifoldResult::calculateCombinedSpinningFriction ||
        gCalculateCombinedContactDampingCallback != &btManifoldResult::calculateCombinedContactDamping ||
        gCalculateCombinedContactStiffnessCallback != &btManifoldResult::calculateCombinedContactStiffness)
        return false;
    if (btGetCurrentEnterProfileZoneFunc() != g_defaultEnterProfile ||
        btGetCurrentLeaveProfileZoneFunc() != g_defaultLeaveProfile)
        return false;
    return info.m_debugDraw == nullptr || info.m_debugDraw->getDebugMode() == btIDebugDraw::DBG_NoDebug;
}

bool objectsMayThread(const btCollisionObject& object0, const btCollisionObject& object1) {
    const auto rigidOrPlain = [](const btCollisionObject& o) {
        const int type = o.getInternalType();
        return type == btCollisionObject::CO_COLLISION_OBJECT || type == btCollisionObject::CO_RIGID_BODY;
    };
    if (!rigidOrPlain(object0) || !rigidOrPlain(object1)) return false;
    const int flags = object0.getCollisionFlags() | object1.getCollisionFlags();
    return gContactAddedCallback == nullptr || (flags & btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK) == 0;
}

void collidePair(btBroadphasePair& pair, const btDispatcherInfo& info) {
    auto* object0 = static_cast<btCollisionObject*>(pair.m_pProxy0->m_clientObject);
    auto* object1 = static_cast<btCollisionObject*>(pair.m_pProxy1->m_clientObject);
    const btCollisionObjectWrapper wrap0(nullptr, object0->getCollisionShape(), object0, object0->getWorldTransform(),
                                         -1, -1);
    const btCollisionObjectWrapper wrap1(nullptr, object1->getCollisionShape(), object1, object1->getWorldTransform(),
                                         -1, -1);
    btManifoldResult result(&wrap0, &wrap1);
    pair.m_algorithm->processCollision(&wrap0, &wrap1, info, &result);
}

void PairStream::reset(std::size_t capacity) {
    m_pairs.resize(capacity);
    m_published.store(0, std::memory_order_relaxed);
    m_next.store(0, std::memory_order_relaxed);
    m_closed.store(false, std::memory_order_relaxed);
}

bool PairStream::push(btBroadphasePair* pair) {
    const std::size_t n = m_published.load(std::memory_order_relaxed);
    if (n >= m_pairs.size()) return false;
    m_pairs[n] = pair;
    m_published.store(n + 1);
    m_waiter.notify();
    return true;
}

void PairStream::close() {
    m_closed.store(true);
    m_waiter.notify();
}

void PairStream::consume(const btDispatcherInfo& info) {
    const PairThreadScope scope;
    for (;;) {
        const std::size_t i = m_next.fetch_add(1, std::memory_order_relaxed);
        // Closed after its last push: once closed, what is published is all there is.
        m_waiter.wait([&] { return i < m_published.load() || m_closed.load(); });
        if (i >= m_published.load()) return;
        collidePair(*m_pairs[i], info);
    }
}

PairThreadScope::PairThreadScope() : m_outer(t_onPairThread) { t_onPairThread = true; }
PairThreadScope::~PairThreadScope() { t_onPairThread = m_outer; }
bool onPairThread() { return t_onPairThread; }

}  // namespace cullide::bullet
