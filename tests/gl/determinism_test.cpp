// The same input gives the same result across runs, thread counts and back-ends (issue #6, determinism).
#include "Compare.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>

namespace cullide::test {
namespace {

std::vector<std::array<std::uint32_t, 4>> flat(const Result& r) {
    std::vector<std::array<std::uint32_t, 4>> out;
    for (const ObjectPair& p : r.pairs)
        for (const TrianglePair& t : p.triangles) out.push_back({p.a, t.a, p.b, t.b});
    return out;  // in result order: must be identical, not just equal as sets
}

TEST(Determinism, SameResultAcrossRunsAndThreadCounts) {
    const auto meshes = randomSoups(123, 24, 120, 0.25);
    const auto objects = asObjects(meshes);
    std::vector<std::array<std::uint32_t, 4>> first;
    for (unsigned threads : {1u, 2u, 5u}) {
        Settings s;
        s.resolution = 128;
        s.threads = threads;
        s.gpuLevels = GpuLevels::Always;
        s.exactThreshold = 0;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, s);
        for (int run = 0; run < 2; ++run) {
            Result r;
            culler->run(objects, r);
            if (first.empty()) first = flat(r);
            EXPECT_EQ(flat(r), first) << "threads " << threads << " run " << run;
            EXPECT_FALSE(first.empty());
        }
    }
    Result reference;
    createReferenceCuller(Settings{})->run(objects, reference);
    EXPECT_EQ(flat(reference), first);
}

}  // namespace
}  // namespace cullide::test
