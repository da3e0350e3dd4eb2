#include "TriangleCases.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace cullide::test {

double up(double x) { return std::nextafter(x, std::numeric_limits<double>::infinity()); }
double down(double x) { return std::nextafter(x, -std::numeric_limits<double>::infinity()); }

std::string str(const Tri& t) {
    std::string s;
    char buf[128];
    for (const Vec3& v : t) {
        std::snprintf(buf, sizeof buf, "{%a, %a, %a} ", v.x(), v.y(), v.z());
        s += buf;
    }
    return s;
}

double dist(const Tri& a, const Tri& b) { return triangleDistance(a[0], a[1], a[2], b[0], b[1], b[2]); }

}  // namespace cullide::test
