// libFuzzer target for the OFF, OBJ and scene readers (scripts/fuzz.sh builds and runs it).
//
// The first byte picks the reader (its value modulo 3: '0' OFF, '1' OBJ, '2' scene JSON), the rest is the input.
// Every input must either parse into a valid mesh/scene or throw ParseError with a bounded message and a line within
// the input; anything else (a crash, a sanitizer report, another exception, a hang, an OOM) is a finding. Mesh
// references in fuzzed scenes resolve against tests/fuzz/meshes (small valid files; reading is read-only).
#include "cullide/io/MeshIO.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

namespace {

using namespace cullide;

[[noreturn]] void finding(const char* what, const std::string& detail) {
    std::fprintf(stderr, "fuzz_readers: %s: %.2000s\n", what, detail.c_str());
    std::abort();
}

void checkMesh(const TriangleMesh& mesh) {
    for (const Vec3& p : mesh.vertices) {
        if (!p.allFinite()) finding("non-finite vertex accepted", "");
    }
    for (const TriangleIndices& t : mesh.triangles) {
        for (const std::uint32_t i : t) {
            if (i >= mesh.vertices.size()) finding("triangle index out of range accepted", std::to_string(i));
        }
    }
}

void checkError(const io::ParseError& e, const std::string& input) {
    const std::string what = e.what();
    // Names are cut at 200 bytes and messages at 1000 (plus the escapes and the "... (N bytes)" notes).
    if (what.size() > 4096) finding("unbounded message", what);
    const auto lines = static_cast<std::size_t>(std::count(input.begin(), input.end(), '\n')) + 1;
    if (e.line() > lines + 1) finding("error line past the end of the input", what);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const int reader = data[0] % 3;
    const std::string input(reinterpret_cast<const char*>(data) + 1, size - 1);
    std::istringstream in(input);
    try {
        if (reader == 0) {
            checkMesh(io::readOff(in, "fuzz.off"));
        } else if (reader == 1) {
            checkMesh(io::readObj(in, "fuzz.obj"));
        } else {
            for (const io::SceneObject& o : io::readScene(in, "fuzz.json", CULLIDE_FUZZ_MESH_DIR)) {
                if (o.mesh == nullptr) finding("scene object without a mesh", o.meshPath);
                checkMesh(*o.mesh);
            }
        }
    } catch (const io::ParseError& e) {
        // An error inside a referenced mesh names that file and its line, not the scene's.
        if (reader != 2 || e.file() == "fuzz.json") checkError(e, input);
    }
    return 0;  // any other exception escapes: libFuzzer reports it as a crash
}
