// CULLIDE (createGpuCuller, or createVisibilityReferenceCuller: the same levels on the CPU reference of the visibility
// test) or the brute-force reference (createReferenceCuller) as a benchmark engine.
#pragma once

#include "Engine.h"

#include "cullide/Culler.h"

#include <memory>
#include <vector>

namespace cullide::bench {

class CullideEngine final : public Engine {
public:
    enum class Kind {
        Gpu,                  ///< createGpuCuller
        VisibilityReference,  ///< createVisibilityReferenceCuller (the visibility test on the CPU reference)
        Exact,                ///< createReferenceCuller: the exact brute-force oracle
    };
    CullideEngine(const Settings& settings, Kind kind);

    void setup(const BenchFrame& first) override;
    void run(const BenchFrame& frame, FrameOutput& out) override;
    nlohmann::json describe() const override;

private:
    Settings m_settings;
    Kind m_kind;
    std::unique_ptr<Culler> m_culler;
    std::vector<Object> m_objects;
    std::vector<Transform> m_transforms;  ///< the rigid objects' poses this frame
    Result m_result;
};

}  // namespace cullide::bench
