// CULLIDE (createGpuCuller) or the brute-force reference (createReferenceCuller) as a benchmark engine.
#pragma once

#include "Engine.h"

#include "cullide/Culler.h"

#include <memory>
#include <vector>

namespace cullide::bench {

class CullideEngine final : public Engine {
public:
    /// `reference`: the exact brute-force oracle instead of the GPU culler.
    CullideEngine(const Settings& settings, bool reference);

    void setup(const BenchFrame& first) override;
    void run(const BenchFrame& frame, FrameOutput& out) override;
    nlohmann::json describe() const override;

private:
    Settings m_settings;
    bool m_reference;
    std::unique_ptr<Culler> m_culler;
    std::vector<Object> m_objects;
    Result m_result;
};

}  // namespace cullide::bench
