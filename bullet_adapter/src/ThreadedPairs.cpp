#include "ThreadedPairs.h"

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btBoxBoxCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexConvexAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexPlaneCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionDispatch/btSphereBoxCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSphereSphereCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSphereTriangleCollisionAlgorithm.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
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
#include <BulletCollision/CollisionShapes/btTetrahedronShape.h>
#include <BulletCollision/CollisionShapes/btTriangleMesh.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <LinearMath/btIDebugDraw.h>
#include <LinearMath/btQuickprof.h>


namespace cullide::bullet {
namespace {

template <typename... T>
bool isOneOf(const std::type_info& type) {
    return ((type == typeid(T)) || ...);
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
    if (type == typeid(btBvhTriangleMeshShape)) {
        const btStridingMeshInterface* mesh = static_cast<const btBvhTriangleMeshShape&>(shape).getMeshInterface();
        return mesh != nullptr && isOneOf<btTriangleIndexVertexArray, btTriangleMesh>(typeid(*mesh));
    }
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

}  // namespace

AlgorithmKind algorithmKindOf(const std::type_info& algorithmClass) {
    // The most frequent first: each comparison with another class may compare names.
    if (algorithmClass == typeid(btConvexConvexAlgorithm)) return AlgorithmKind::ConvexConvex;
    if (algorithmClass == typeid(btBoxBoxCollisionAlgorithm)) return AlgorithmKind::Convex;
    if (algorithmClass == typeid(btConvexConcaveCollisionAlgorithm)) return AlgorithmKind::ConvexConcave;
    if (isOneOf<btSphereSphereCollisionAlgorithm, btSphereBoxCollisionAlgorithm, btSphereTriangleCollisionAlgorithm,
                btConvexPlaneCollisionAlgorithm>(algorithmClass))
        return AlgorithmKind::Convex;
    return AlgorithmKind::Other;
}

bool worthHandingOff(AlgorithmKind kind) {
    return kind == AlgorithmKind::ConvexConvex || kind == AlgorithmKind::ConvexConcave;
}

std::size_t typicalCost(AlgorithmKind kind) {
    switch (kind) {
        case AlgorithmKind::Convex:
            return 1;
        case AlgorithmKind::ConvexConvex:
            return 4;
        case AlgorithmKind::ConvexConcave:
            return 16;
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
            return bulletConvex(convex) && bulletConcave(concave) &&
                   (bulletConvexFunc(triangleFunc) ||
                    (triangleFunc != nullptr &&
                     typeid(*triangleFunc) == typeid(btSphereTriangleCollisionAlgorithm::CreateFunc)));
        }
        case AlgorithmKind::Other:
            break;
    }
    return false;
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
