// Uses the installed culler: the reference culler needs no GL, so this runs anywhere.
#include <cullide/Culler.h>

#include <cstdio>

int main() {
    cullide::TriangleMesh a, b;
    a.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    a.triangles = {{0, 1, 2}};
    b.vertices = {{0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.8, 0.8, 0}};
    b.triangles = {{0, 1, 2}};
    std::vector<cullide::Object> objects(2);
    objects[0].mesh = &a;
    objects[1].mesh = &b;
    cullide::Result result;
    cullide::createReferenceCuller(cullide::Settings{})->run(objects, result);
    std::printf("consumer: %zu pair(s)\n", result.pairs.size());
    return result.pairs.size() == 1 ? 0 : 1;
}
