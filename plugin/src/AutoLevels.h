// GpuLevels::Auto: whether a frame runs the GPU visibility levels, decided by timing both paths on the scene itself.
#pragma once

#include <cstddef>
#include <string>

namespace cullide {

/// The trial: the first frames of a scene alternate the two paths (CPU, GPU, CPU, GPU); the first frame of each is
/// a warm-up (static caches, the first upload of the device's resident region) and is not compared; the second of
/// each is timed. From then on the faster path runs, until the scene's triangle count leaves [half, twice] the
/// count it was measured at, once the decision has held for a hold of frames (kMinFramesBetweenTrials); then the
/// trial starts again. Both paths give the same pairs, so trial frames are ordinary frames; a trial costs at most
/// two frames on the slower path per hold + 4 frames. A trial that repeats the decision before it, with the slower
/// path at least kClearLoss times the faster, doubles the hold (up to kMaxFramesBetweenTrials): a scene whose
/// colliding set keeps changing size does not pay for a far slower path (a GPU that loses by 5x on a machine of
/// many cores) every two seconds. Any other trial sets the hold back to kMinFramesBetweenTrials.
/// No trial frame stalls a frame loop: a GPU trial frame gets a budget (trialBudgetMs: the last CPU frame's time plus
/// 1 ms); the culler abandons GPU levels that run past it and finishes the frame on the CPU path, so such a frame
/// costs at most about twice a CPU frame plus 1 ms, and its time (recorded as the GPU's) makes the CPU path win. Once
/// the GPU levels won, a new trial is skipped (the hold doubled instead) while the CPU path, scaled to the scene's
/// new size, would take more than twice the GPU frame plus 1 ms: a CPU trial frame would then stall the loop.
/// GpuCuller runs the levels under Auto on hardware devices only (createGpuCuller; a software renderer never wins).
class AutoLevels {
public:
    enum class Path { Cpu, Gpu };

    /// The path for the next frame of a scene with `triangles` triangles (those the levels would see). A frame
    /// without triangles runs the CPU path and is no trial frame.
    Path choose(std::size_t triangles);
    /// The frame just run on `path` (as returned by choose()) took `ms` (wall time of the whole frame).
    void record(Path path, double ms);
    /// The time a GPU trial frame may spend before its GPU levels are abandoned (the last CPU frame's time plus
    /// kBudgetSlackMs); 0: no limit (no CPU frame yet, or not a trial frame).
    double trialBudgetMs() const;

    /// A trial is under way (or none has started: the first frame with triangles starts one).
    bool measuring() const { return m_step < kTrialFrames; }
    /// Frames the decision holds before a change of the scene's size may start a new trial.
    int holdFrames() const { return m_holdFrames; }
    /// "measuring", or "gpu" / "cpu": the faster path of the last trial.
    std::string decision() const;
    /// The timed trial frames of the last completed trial, in ms (0 before the first completes).
    double cpuMs() const { return m_cpuMs; }
    double gpuMs() const { return m_gpuMs; }

private:
    static constexpr int kTrialFrames = 4;
    static constexpr int kMinFramesBetweenTrials = 120;
    static constexpr int kMaxFramesBetweenTrials = 120 * 32;
    static constexpr double kClearLoss = 2.0;
    static constexpr double kBudgetSlackMs = 1.0;
    static Path trialPath(int step) { return step % 2 == 0 ? Path::Cpu : Path::Gpu; }

    int m_step = 0;                   ///< trial frames done; kTrialFrames = decided
    int m_framesDecided = 0;          ///< frames run on the decision since the last trial
    int m_holdFrames = kMinFramesBetweenTrials;
    bool m_decided = false;           ///< some trial has completed (m_decision is its outcome)
    bool m_pending = false;           ///< the path last chosen is a trial frame, not yet recorded
    std::size_t m_triangles = 0;      ///< triangle count of the scene when the trial started
    double m_trialCpuMs = 0.0, m_trialGpuMs = 0.0;
    double m_cpuMs = 0.0, m_gpuMs = 0.0;
    double m_lastCpuFrameMs = 0.0;    ///< the last trial frame on the CPU path, warm-up or timed
    Path m_decision = Path::Cpu;
};

}  // namespace cullide
