// Command line of cullide-bench-run.
#pragma once

#include <string>

namespace cullide::bench {

struct RunArgs {
    std::string scene = "env1";
    std::string engine = "cullide";
    std::string tag = "side";   ///< which part of the report the record belongs to
    std::string truthPath;      ///< exact engine: written; others: read when present
    std::string outPath;        ///< JSON line appended here (else stdout)
    int objects = -1;
    int trianglesPerObject = -1;
    int frames = 5;
    int warmup = 1;             ///< untimed frames first (shader compilation, caches)
    int resolution = 256;
    int groupSize = 32;
    int maxIterations = 4;      ///< CULLIDE engines: Settings::maxIterations
    double minPruneFraction = 0.0625;  ///< CULLIDE engines: Settings::minPruneFraction
    int threads = -1;           ///< CULLIDE engines: Settings::threads (0: every core); -1: the engine's own
    int sampleEvery = 10;       ///< breakable: compare with the exact answer every n-th frame
};

}  // namespace cullide::bench
