// The image-space visibility test of CULLIDE on the GPU (OpenGL 4.5 through headless EGL): the PruningBackend that
// production runs. A level runs on the device as a chain: its records are built there (build.comp), the passes over
// them are dispatched indirectly, and each iteration's last work group decides whether the next one runs, fits its
// view and writes its arguments (iteration.glsl). The C++ side issues the level's iterations without waiting and reads
// back once at the end: the counters, the chain and the alive set as bits. A frame's deferred levels (one per cluster)
// are read back together: one wait per frame.
#pragma once

#include "CullerBackends.h"
#include "PruningBackend.h"
#include "cullide/Settings.h"

#include <memory>
#include <string>
#include <vector>

namespace cullide::gl {

class VisibilityPass final : public PruningBackend {
public:
    /// Opens the EGL context (Settings::device) and builds the programs of Settings::backend. Throws
    /// GlUnavailableError without a usable GL device.
    explicit VisibilityPass(const Settings& settings, const GlBackendOptions& options = {});
    ~VisibilityPass() override;

    void beginFrame() override;
    void upload(const GpuGeometry& geometry, Stats& stats) override;
    void forgetUploads() override;
    /// Buffer capacities plus the view images.
    std::size_t deviceBytes() const override;
    std::string renderer() const override;
    std::string device() const override;
    bool hardwareDevice() const override;

    void pruneLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                    LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) override;
    void pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                         std::vector<IterationTrace>* trace) override;
    void settle(Stats& stats) override;
    void pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                            std::vector<IterationTrace>* trace) override;
    bool collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) override;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::gl
