// The image-space visibility test of CULLIDE on the GPU (OpenGL 4.5 through headless EGL): the PruningBackend that
// production runs. The iterations' alive set, records and counters stay on the device; the records are built there
// (build.comp) and the passes over them are dispatched indirectly, so a build is never waited for. The one read-back
// of an iteration brings its counters and the alive set as bits: nothing else is waited for.
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

    void upload(const GpuGeometry& geometry, Stats& stats) override;
    void forgetUploads() override;
    /// Buffer capacities plus the view images.
    std::size_t deviceBytes() const override;
    std::string renderer() const override;
    std::string device() const override;

    void beginLevel(const LevelItems& items, const View& view, LevelStats& level, Stats& stats) override;
    IterationResult iterate(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) override;
    void readAlive(std::vector<std::uint8_t>& alive, LevelStats& level, Stats& stats) override;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::gl
