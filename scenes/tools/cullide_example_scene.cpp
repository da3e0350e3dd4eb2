// Writes an example scene for cullide-pairs: OFF meshes plus scene.json (tori, open cylinders and spheres, some
// interpenetrating). Usage: cullide-example-scene OUTDIR [SEED]
#include "cullide/io/MeshIO.h"
#include "cullide/scenes/Procedural.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
    if (argc < 2 || std::string(argv[1]) == "--help") {
        std::fprintf(stderr, "usage: cullide-example-scene OUTDIR [SEED]\n");
        return argc < 2 ? 2 : 0;
    }
    namespace fs = std::filesystem;
    const fs::path dir = argv[1];
    const unsigned seed = argc > 2 ? static_cast<unsigned>(std::strtoul(argv[2], nullptr, 10)) : 1u;
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) {
        std::fprintf(stderr, "cullide-example-scene: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
        return 2;
    }
    std::string json = "{\"objects\": [\n";
    const int count = 12;
    for (int i = 0; i < count; ++i) {
        cullide::TriangleMesh mesh;
        switch (i % 3) {
            case 0: mesh = cullide::scenes::makeTorus(0.3, 0.08, 64, 24); break;
            case 1: mesh = cullide::scenes::makeOpenCylinder(0.12, 0.6, 32, 8); break;
            default: mesh = cullide::scenes::makeSphere(0.2, 32, 16); break;
        }
        const std::string name = "object" + std::to_string(i) + ".off";
        std::ofstream out(dir / name);
        cullide::io::writeOff(mesh, out);
        // Objects on a jittered 3 x 2 x 2 grid, spaced so that neighbours interpenetrate a little.
        const double jitter = 0.05 * static_cast<double>((seed * 2654435761u + static_cast<unsigned>(i) * 40503u) % 100) / 100.0;
        const double x = 0.45 * (i % 3) + jitter, y = 0.45 * ((i / 3) % 2), z = 0.45 * (i / 6);
        const double c = std::cos(0.7 * i), s = std::sin(0.7 * i);
        char transform[512];
        std::snprintf(transform, sizeof transform, "[%g, %g, 0, %g, %g, %g, 0, %g, 0, 0, 1, %g, 0, 0, 0, 1]", c, -s, x,
                      s, c, y, z);
        json += "  {\"mesh\": \"" + name + "\", \"transform\": " + transform + "}" + (i + 1 < count ? ",\n" : "\n");
    }
    json += "]}\n";
    std::ofstream(dir / "scene.json") << json;
    std::printf("%s\n", (dir / "scene.json").c_str());
    return 0;
}
