// A collision engine under test: it is set up once on the first frame (not timed) and then computes, per frame,
// the intersecting triangle pairs (or what it can report of them) of the frame's meshes.
#pragma once

#include "BenchScene.h"
#include "PairSet.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cullide::bench {

struct StageTime {
    std::string name;
    double ms = 0.0;
};

struct FrameOutput {
    std::vector<StageTime> stages;  ///< wall ms per stage, in pipeline order; they add up to totalMs
    double totalMs = 0.0;
    PairSet pairs;                   ///< what the engine reported (finished)
    bool trianglePairsKnown = true;  ///< false: only object pairs are meaningful
    std::optional<std::size_t> candidates;  ///< triangle pairs handed to an exact test (the cost of culling)
    std::size_t contacts = 0;        ///< contact points (Bullet)
    std::size_t bytesUploaded = 0;
    std::size_t bytesReadBack = 0;
    std::size_t gpuDeviceBytes = 0;  ///< culler's buffers and images on its GL device
    std::size_t draws = 0;           ///< GL draws and dispatches (CULLIDE)
    std::size_t blockingReadBacks = 0;  ///< read-backs that waited for the device (CULLIDE)
    std::optional<double> gpuTimerMs;  ///< GPU time of the levels from timer queries, where valid (CULLIDE)
    nlohmann::json levels;           ///< per GPU level: items per iteration, draws, CPU and GPU ms (CULLIDE)
    long minorFaults = 0;  ///< the process's minor page faults during the frame (set by the harness, frame scenes)
    /// The culler's worker pool during the frame (Stats::poolCalls, poolWorkerWakes, poolCallerSleeps; CULLIDE).
    std::optional<std::array<std::size_t, 3>> pool;

    void clear() { *this = FrameOutput{}; }
};

struct EngineOptions {
    int resolution = 256;  ///< CULLIDE image resolution (GPU levels)
    int groupSize = 32;
    int maxIterations = 4;  ///< Settings::maxIterations
    double minPruneFraction = 0.0625;  ///< Settings::minPruneFraction
    int threads = -1;  ///< Settings::threads of the CULLIDE engines (0: every core); -1: the engine's own
};

class Engine {
public:
    virtual ~Engine() = default;
    Engine() = default;
    Engine(const Engine&) = delete;
    Engine& operator=(const Engine&) = delete;

    /// Builds the engine's structures for the scene (not timed).
    virtual void setup(const BenchFrame& first) = 0;
    virtual void run(const BenchFrame& frame, FrameOutput& out) = 0;
    /// Fields for the results record: mode, resolution, gpu_levels, threads, renderer, device, ...
    virtual nlohmann::json describe() const = 0;
};

/// exact | cullide | cullide-1t | cullide-gpu | cullide-sampled | bullet-dbvt | bullet-sap | fcl | fcl-aabb.
/// Throws std::invalid_argument for an unknown (or not built) engine.
std::unique_ptr<Engine> makeEngine(const std::string& name, const EngineOptions& options);
/// The engine names this binary was built with.
std::vector<std::string> engineNames();

}  // namespace cullide::bench
