// The scenes' data directory (Environments.h): the environment variable overrides the source tree.
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace cullide::scenes {
namespace {

TEST(DataDir, EnvironmentVariableOverridesTheSourceTree) {
    const char* old = std::getenv("CULLIDE_DATA_DIR");
    const std::string saved = old != nullptr ? old : "";
    ::setenv("CULLIDE_DATA_DIR", "/some/where", 1);
    EXPECT_EQ(defaultDataDir(), "/some/where");
    ::unsetenv("CULLIDE_DATA_DIR");
    const std::string fallback = defaultDataDir();
    EXPECT_GE(fallback.size(), std::string("/data/meshes").size());
    EXPECT_EQ(fallback.substr(fallback.size() - 12), "/data/meshes");
    if (old != nullptr) ::setenv("CULLIDE_DATA_DIR", saved.c_str(), 1);
}

}  // namespace
}  // namespace cullide::scenes
