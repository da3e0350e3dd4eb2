// Per-frame records of a demo run, written as frames.csv, and the medians/worst figures of summary.json.
#pragma once

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

namespace cullide::demo {

struct FrameRecord {
    int frame = 0;
    /// Which path culled the frame: "gpu-levels" or "cpu-path" (the culler ran, on its GPU visibility levels or its
    /// CPU path), "abandoned" (an Auto trial's culler ran past its budget), "not-culled" (breakable: no pair went
    /// through the culler this step; its pairs got Bullet's contacts).
    std::string path;
    std::size_t culledPairs = 0;        ///< breakable: body pairs that went through the culler
    std::size_t prunedPairs = 0;        ///< ... of which it proved apart
    /// The potentially colliding set level by level where the GPU levels ran: "name:in>out" per level, in order
    /// (e.g. "groups:812>130 triangles:4160>377"); empty on the CPU path.
    std::string levels;
    std::size_t objects = 0;            ///< objects with triangles (bodies in the breakable scene)
    std::size_t triangles = 0;
    std::size_t prepassObjects = 0;     ///< objects left by the CPU box pre-pass
    std::size_t prepassGroups = 0;      ///< sub-objects (groups of k triangles) left by the pre-pass
    std::size_t pcsObjects = 0;         ///< object-level PCS
    std::size_t pcsTriangles = 0;       ///< triangle-level PCS (all objects)
    std::size_t candidatePairs = 0;     ///< triangle pairs handed to the exact test
    /// Environments: exactly intersecting triangle pairs. Breakable: the candidate triangle pairs handed to
    /// Bullet's narrow phase (Bullet's triangle routines are the exact test there).
    std::size_t trianglePairs = 0;
    std::size_t broadphasePairs = 0;    ///< Bullet overlapping pairs (breakable)
    std::size_t contacts = 0;           ///< Bullet contact points (breakable)
    std::size_t newPieces = 0;          ///< bodies created by fracture this frame
    double prepassMs = 0, gpuLevelsMs = 0, exactMs = 0, cullMs = 0, narrowphaseMs = 0, solverMs = 0,
           fractureMs = 0, frameMs = 0;
    long missed = -1;                   ///< triangle pairs missed against the exact reference; -1 = not checked
};

void writeCsvHeader(std::ostream& out);
void writeCsvRow(std::ostream& out, const FrameRecord& r);

struct Figures {
    double median = 0, worst = 0, mean = 0;
};
/// Median / worst / mean of one column over the records (0s when empty).
Figures figuresOf(const std::vector<FrameRecord>& records, double FrameRecord::*column);

}  // namespace cullide::demo
