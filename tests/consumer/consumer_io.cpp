// Uses the installed io library beside the culler: reads an OFF mesh (the path in argv[1]), culls it against a
// shifted copy with the reference culler (no GL), writes a PNG (argv[2]) and reads it back. Exit 0 when all agree.
#include <cullide/Culler.h>
#include <cullide/io/Image.h>
#include <cullide/io/MeshIO.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: consumer_io MESH.off OUT.png\n");
        return 2;
    }
    try {
        const cullide::TriangleMesh a = cullide::io::readMesh(argv[1]);
        cullide::TriangleMesh b = a;
        for (cullide::Vec3& p : b.vertices) p += cullide::Vec3(0.5, 0.5, 0.5);
        std::vector<cullide::Object> objects(2);
        objects[0].mesh = &a;
        objects[1].mesh = &b;
        cullide::Result result;
        cullide::createReferenceCuller(cullide::Settings{})->run(objects, result);

        cullide::Image image;
        image.width = 3;
        image.height = 2;
        for (int i = 0; i < image.width * image.height; ++i) {
            image.rgba.insert(image.rgba.end(), {std::uint8_t(40 * i), std::uint8_t(255 - 40 * i), 7, 255});
        }
        cullide::io::writePng(argv[2], image);
        const cullide::Image back = cullide::io::readPng(argv[2]);

        std::printf("consumer_io: %zu triangles read, %zu pair(s), PNG %dx%d read back %s\n", a.triangles.size(),
                    result.pairs.size(), back.width, back.height, back.rgba == image.rgba ? "equal" : "DIFFERENT");
        return a.triangles.size() == 12 && result.pairs.size() == 1 && back.width == image.width &&
                       back.height == image.height && back.rgba == image.rgba
                   ? 0
                   : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "consumer_io: %s\n", e.what());
        return 1;
    }
}
