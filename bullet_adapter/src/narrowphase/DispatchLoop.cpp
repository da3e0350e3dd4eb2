#include "narrowphase/DispatchLoop.h"

#include "narrowphase/ApartPairs.h"

namespace cullide::bullet {

bool DispatchLoop::processOverlap(btBroadphasePair& pair) {
    if (skipIfApart(pair, m_dispatcher, m_scratch)) {
        ++skipped;
        return false;
    }
    const AlgorithmKind kind = m_threadable != nullptr ? (*m_threadable)(pair) : AlgorithmKind::Other;
    if (!worthHandingOff(kind)) {
        btCollisionDispatcher::defaultNearCallback(pair, m_dispatcher, m_info);
    } else {
        threadableCost += typicalCost(kind);
        if (m_stream == nullptr || !m_stream->push(&pair)) collidePair(pair, m_info);
    }
    return false;  // the pair stays in the cache
}

}  // namespace cullide::bullet
