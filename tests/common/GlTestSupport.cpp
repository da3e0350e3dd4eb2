#include "GlTestSupport.h"

#include <cstdlib>
#include <cstring>

namespace cullide::test {

bool runningInCi() {
    const char* ci = std::getenv("CI");
    return ci != nullptr && (std::strcmp(ci, "true") == 0 || std::strcmp(ci, "1") == 0);
}

std::unique_ptr<Culler> makeGpuCuller(const Settings& settings, std::string& whyNot) {
    try {
        return createGpuCuller(settings);
    } catch (const GlUnavailableError& e) {
        whyNot = e.what();
        return nullptr;
    }
}

std::unique_ptr<SnapshotRenderer> makeSnapshotRenderer(std::string& whyNot) {
    try {
        return SnapshotRenderer::create();
    } catch (const GlUnavailableError& e) {
        whyNot = e.what();
        return nullptr;
    }
}

}  // namespace cullide::test
