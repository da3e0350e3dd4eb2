// A GL error in the middle of a frame (issue #6): the frame falls back to the CPU path and still reports every
// pair; the culler keeps working once the error is gone. Errors are injected with CULLIDE_INJECT_GL_ERROR (see
// plugin/src/gl/GlApi.h), which makes the named GL check report GL_INVALID_OPERATION.
#include "Compare.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace cullide::test {
namespace {

/// Sets an environment variable for the scope of one test.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const char* value) : m_name(name) { setenv(name, value, 1); }
    ~ScopedEnv() { unsetenv(m_name); }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* m_name;
};

void expectSameAsReference(const Result& reference, const Result& result, const char* what) {
    const Comparison c = compare(reference, result);
    EXPECT_EQ(c.missed, 0u) << what << ": " << c.firstMissed;
    EXPECT_EQ(c.spurious, 0u) << what;
    EXPECT_TRUE(c.objectPairsEqual) << what;
}

TEST(GlFailure, ErrorMidFrameFallsBackWithoutMissingAPair) {
    for (Pipeline pipeline : {Pipeline::Auto, Pipeline::Paper}) {
        Settings settings;
        settings.gpuLevels = GpuLevels::Always;  // GPU levels also on llvmpipe, where Auto skips them
        settings.exactThreshold = 0;
        settings.pipeline = pipeline;
        settings.resolution = 64;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
        const auto meshes = randomSoups(11, 40, 100, 0.08);
        auto objects = asObjects(meshes);
        for (std::size_t i = 0; i < objects.size(); i += 3) objects[i].staticKey = i + 1;  // resident on the device
        Result reference, healthy, failing, recovered;
        createReferenceCuller(settings)->run(objects, reference);
        ASSERT_GT(trianglePairs(reference).size(), 0u);

        culler->run(objects, healthy);
        EXPECT_EQ(healthy.stats.gpuFallbacks, 0u);
        EXPECT_FALSE(healthy.stats.levels.empty()) << "the GPU levels must run in this test";
        expectSameAsReference(reference, healthy, "healthy");
        {
            ScopedEnv inject("CULLIDE_INJECT_GL_ERROR", "visibility iteration");
            culler->run(objects, failing);
        }
        EXPECT_EQ(failing.stats.gpuFallbacks, 1u);
        EXPECT_NE(failing.stats.gpuError.find("OpenGL error 0x0502"), std::string::npos) << failing.stats.gpuError;
        expectSameAsReference(reference, failing, "GL error mid-frame");

        culler->run(objects, recovered);  // the error is gone: the GPU levels run again
        EXPECT_EQ(recovered.stats.gpuFallbacks, 0u) << recovered.stats.gpuError;
        expectSameAsReference(reference, recovered, "after the error");
    }
}

TEST(GlFailure, InjectionOnlyMatchesTheNamedCheck) {
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;
    settings.exactThreshold = 0;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    const auto meshes = randomSoups(12, 6, 40, 0.3);
    Result result;
    ScopedEnv inject("CULLIDE_INJECT_GL_ERROR", "no check has this name");
    culler->run(asObjects(meshes), result);
    EXPECT_FALSE(result.stats.levels.empty()) << "the GPU levels must run for this test to mean anything";
    EXPECT_EQ(result.stats.gpuFallbacks, 0u);
}

}  // namespace
}  // namespace cullide::test
