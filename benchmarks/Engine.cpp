#include "Engine.h"

#include "BulletEngine.h"
#include "CullideEngine.h"
#ifdef CULLIDE_BENCH_FCL
#include "FclEngine.h"
#endif

#include <stdexcept>

namespace cullide::bench {

std::vector<std::string> engineNames() {
    std::vector<std::string> names = {"exact",          "cullide",         "cullide-1t",  "cullide-cpu",
                                      "cullide-gpu",    "cullide-gpu-exact", "cullide-raster", "cullide-sampled",
                                      "cullide-sampled-reference",
                                      "bullet-dbvt",    "bullet-sap"};
#ifdef CULLIDE_BENCH_FCL
    names.push_back("fcl");
    names.push_back("fcl-aabb");
#endif
    return names;
}

std::unique_ptr<Engine> makeEngine(const std::string& name, const EngineOptions& options) {
    Settings s;
    s.resolution = options.resolution;
    s.groupSize = options.groupSize;
    s.maxIterations = options.maxIterations;
    s.minPruneFraction = options.minPruneFraction;
    if (options.threads >= 0) s.threads = static_cast<unsigned>(options.threads);
    if (name == "exact") return std::make_unique<CullideEngine>(s, CullideEngine::Kind::Exact);
    if (name == "cullide") return std::make_unique<CullideEngine>(s, CullideEngine::Kind::Gpu);
    if (name == "cullide-1t") {
        s.threads = 1;  // whatever --threads says: the engine's name is its thread count
        return std::make_unique<CullideEngine>(s, CullideEngine::Kind::Gpu);
    }
    if (name == "cullide-cpu") {  // the CPU path alone: what Auto weighs the GPU levels against
        s.gpuLevels = GpuLevels::Never;
        return std::make_unique<CullideEngine>(s, CullideEngine::Kind::Gpu);
    }
    if (name == "cullide-gpu-exact") {  // the GPU levels and the exact stage's search on the device, everywhere
        s.gpuLevels = GpuLevels::Always;
        s.deviceExact = DeviceExact::Always;
        return std::make_unique<CullideEngine>(s, CullideEngine::Kind::Gpu);
    }
    if (name == "cullide-gpu" || name == "cullide-raster" || name == "cullide-sampled") {
        s.gpuLevels = GpuLevels::Always;
        if (name == "cullide-sampled") s.mode = Mode::Sampled;
        if (name == "cullide-raster") s.backend = Backend::Raster;
        return std::make_unique<CullideEngine>(s, CullideEngine::Kind::Gpu);
    }
    if (name == "cullide-sampled-reference") {  // cullide-sampled's levels on the CPU reference of the visibility test
        s.gpuLevels = GpuLevels::Always;
        s.mode = Mode::Sampled;
        return std::make_unique<CullideEngine>(s, CullideEngine::Kind::VisibilityReference);
    }
    if (name == "bullet-dbvt") return std::make_unique<BulletEngine>(BulletEngine::Broadphase::Dbvt);
    if (name == "bullet-sap") return std::make_unique<BulletEngine>(BulletEngine::Broadphase::AxisSweep);
#ifdef CULLIDE_BENCH_FCL
    if (name == "fcl") return std::make_unique<FclEngine>(FclEngine::Volume::Obbrss);
    if (name == "fcl-aabb") return std::make_unique<FclEngine>(FclEngine::Volume::Aabb);
#endif
    throw std::invalid_argument("unknown or not built engine '" + name + "'");
}

}  // namespace cullide::bench
