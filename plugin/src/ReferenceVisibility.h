// The CPU reference of CULLIDE's visibility test: the PruningBackend that computes, pixel by pixel, what the
// shaders compute (shaders/common.glsl, visit.glsl, scan.glsl, iteration.glsl) in the same float operations in the
// same order: the same primitive set-up, the same pixel grid and coverage test (pixel centres in sampled mode; the
// conservative square and depth range in reliable mode), the same quantized per-pixel "nearest and farthest other
// owner" bookkeeping and the same survival rule. GL tests assert that the GL backend keeps exactly the items this
// one keeps, iteration by iteration; unit tests run whole culling frames on it without GL.
//
// Single-threaded and unoptimised: a test oracle, not a production path (Settings::resolution^2 pixels per view).
#pragma once

#include "PruningBackend.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <vector>

namespace cullide {

class ReferenceVisibility final : public PruningBackend {
public:
    explicit ReferenceVisibility(const Settings& settings);

    void beginFrame() override { m_deferred.clear(); }
    void upload(const GpuGeometry& geometry, Stats& stats) override;
    void forgetUploads() override {}
    std::size_t deviceBytes() const override { return 0; }
    std::string renderer() const override { return "cpu-visibility-reference"; }
    std::string device() const override { return "cpu"; }

    /// The level's loop of iterations on the CPU: the reference of the GL back-end's chain on the device.
    void pruneLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                    LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) override;
    /// pruneLevel at once: nothing is left to wait for.
    void pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                         std::vector<IterationTrace>* trace) override;
    void settle(Stats&) override {}
    /// pruneLevel at once; collect() hands the survivors over (and never waits).
    void pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                            std::vector<IterationTrace>* trace) override;
    bool collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) override;

private:
    /// One iteration: both views along every enabled axis over the alive items; an item stays alive when it is not
    /// fully visible in any of them.
    IterationResult iterate(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats);

    Settings m_settings;

    /// start.comp's copy: a level described by its objects expanded into m_expanded (a primitive and an owner per
    /// item), the items that start alive into m_alive (m_parentAlive holding the last level's where it inherits), and
    /// the first view and owner-id bits fitted to them.
    void startByObjects(const LevelItems& items, double coordinateBound, View& view, std::uint32_t& idBits);

    const GpuGeometry* m_geometry = nullptr;
    GpuGeometry m_mapped;  ///< the upload with its mapped meshes' positions, where it has some
    LevelItems m_expanded;  ///< a level described by its objects, with its primitives and owners
    const LevelItems* m_items = nullptr;
    std::vector<std::uint8_t> m_alive;        ///< of the level being run; after it, of the last level
    std::vector<std::uint8_t> m_parentAlive;  ///< the last level's, while a level inherits it
    std::vector<std::uint32_t> m_flags;
    std::vector<DeferredLevel> m_deferred;  ///< the levels run since the last collect()
    std::vector<std::uint32_t> m_near1, m_far1, m_near2, m_far2;  ///< one view's images
};

}  // namespace cullide
