// The paper's three environments (section 5) and seeded random scenes.
//
// Every environment computes frame f in closed form from its seed (no state carried between frames), so frames can
// be visited in any order and the same (seed, frame) always yields the same meshes. Random numbers come from
// std::mt19937_64 (whose output sequence the standard fixes) with our own uniform mapping, because the std
// distributions differ between standard library implementations.
#include "cullide/scenes/Environments.h"

#include "cullide/io/MeshIO.h"
#include "cullide/scenes/Procedural.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>

namespace cullide::scenes {

namespace {

constexpr double kPi = 3.1415926535897932384626433832795;
constexpr double kTwoPi = 2.0 * kPi;
/// Simulated time per frame (seconds); velocities below are per second.
constexpr double kFrameDt = 1.0 / 30.0;

class Rng {
public:
    explicit Rng(std::uint64_t seed) : m_gen(seed) {}
    /// Uniform in [0, 1), 53 random bits.
    double uniform() { return static_cast<double>(m_gen() >> 11) * (1.0 / 9007199254740992.0); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    /// Uniform integer in [lo, hi] (hi >= lo).
    int integer(int lo, int hi) {
        const auto span = static_cast<std::uint64_t>(static_cast<std::int64_t>(hi) - lo + 1);
        return static_cast<int>(lo + static_cast<std::int64_t>(m_gen() % span));
    }
    Vec3 inBox(const Vec3& lo, const Vec3& hi) {
        return {uniform(lo.x(), hi.x()), uniform(lo.y(), hi.y()), uniform(lo.z(), hi.z())};
    }
    Vec3 unitVector() {
        const double z = uniform(-1.0, 1.0);
        const double phi = uniform(0.0, kTwoPi);
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        return {s * std::cos(phi), s * std::sin(phi), z};
    }
    /// Uniformly distributed rotation (Shoemake's method).
    Eigen::Quaterniond rotation() {
        const double u1 = uniform(), u2 = uniform(0.0, kTwoPi), u3 = uniform(0.0, kTwoPi);
        const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
        return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3))
            .normalized();
    }

private:
    std::mt19937_64 m_gen;
};

/// Position on [lo, hi] of a point starting at x0 with velocity v, reflected at both ends (closed form).
double bounce(double x0, double v, double t, double lo, double hi) {
    const double length = hi - lo;
    if (!(length > 0.0)) return 0.5 * (lo + hi);
    double s = std::fmod(x0 - lo + v * t, 2.0 * length);
    if (s < 0.0) s += 2.0 * length;
    return lo + (s <= length ? s : 2.0 * length - s);
}

Vec3 bounce(const Vec3& x0, const Vec3& v, double t, double lo, double hi) {
    return {bounce(x0.x(), v.x(), t, lo, hi), bounce(x0.y(), v.y(), t, lo, hi), bounce(x0.z(), v.z(), t, lo, hi)};
}

int roundPositive(double x, int minimum) { return std::max(minimum, static_cast<int>(std::lround(x))); }

/// Signed volume enclosed by a closed, outward-oriented mesh.
double signedVolume(const TriangleMesh& m) {
    double v = 0.0;
    for (const auto& t : m.triangles) v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]]));
    return v / 6.0;
}

/// Scales and recentres a mesh in place: bounding-box centre at the origin, largest extent = `size`.
void normalize(TriangleMesh& m, double size) {
    const Aabb box = boundsOf(m);
    if (box.isEmpty()) return;
    const Vec3 centre = 0.5 * (box.min + box.max);
    const double extent = box.extent().maxCoeff();
    const double scale = extent > 0.0 ? size / extent : 1.0;
    for (Vec3& p : m.vertices) p = (p - centre) * scale;
}

void requireNonNegative(int value, const char* what) {
    if (value < 0) throw std::invalid_argument(std::string(what) + " must be non-negative");
}

// ---------------------------------------------------------------------------------------------------------------
// Environment 1: deforming open cylinders in the unit cube.

class Env1 final : public Environment {
public:
    Env1(std::uint64_t seed, int count, int trianglesPerObject) {
        requireNonNegative(count, "env1 object count");
        Rng rng(seed ^ 0x656e76315f63796cULL);
        const int segments = roundPositive(std::sqrt(std::max(trianglesPerObject, 6) / 2.0), 3);
        const int rings = roundPositive(std::max(trianglesPerObject, 6) / (2.0 * segments), 1);
        // Volume of the mesh's prism (a regular `segments`-gon section) per unit r^2 h.
        const double sectionFactor = 0.5 * segments * std::sin(kTwoPi / segments);

        std::vector<double> weights(static_cast<std::size_t>(count));
        double weightSum = 0.0;
        for (double& w : weights) weightSum += (w = rng.uniform(0.7, 1.3));

        for (int i = 0; i < count; ++i) {
            Cylinder c;
            // Solid volumes share the target density; the pulse adds ~P^2/2 on average, hence the correction.
            c.pulseAmp = rng.uniform(0.06, 0.12);
            const double volume = kDensity * weights[static_cast<std::size_t>(i)] / weightSum /
                                  (1.0 + 0.5 * c.pulseAmp * c.pulseAmp);
            const double aspect = rng.uniform(1.5, 3.0);  // height / diameter
            c.radius = std::cbrt(volume / (sectionFactor * 2.0 * aspect));
            c.height = 2.0 * aspect * c.radius;
            c.base = makeOpenCylinder(c.radius, c.height, segments, rings);
            c.pulseFreq = rng.uniform(1.5, 3.5);
            c.pulseWaves = rng.uniform(0.5, 1.5);
            c.pulsePhase = rng.uniform(0.0, kTwoPi);
            c.bendAmp = rng.uniform(0.1, 0.25) * c.height;
            c.bendFreq = rng.uniform(0.8, 2.0);
            c.bendPhase = rng.uniform(0.0, kTwoPi);
            c.bendTurn = rng.uniform(-1.5, 1.5);
            c.twistAmp = rng.uniform(0.3, 0.8);
            c.twistFreq = rng.uniform(0.5, 1.5);
            c.twistPhase = rng.uniform(0.0, kTwoPi);
            c.bound = std::hypot(0.5 * c.height, c.radius * (1.0 + c.pulseAmp)) + c.bendAmp * (2.0 / 3.0);
            const double lo = std::min(c.bound, 0.5), hi = std::max(1.0 - c.bound, 0.5);
            c.start = rng.inBox(Vec3::Constant(lo), Vec3::Constant(hi));
            c.velocity = rng.unitVector() * rng.uniform(0.1, 0.3);
            c.orientation = rng.rotation();
            c.spinAxis = rng.unitVector();
            c.spinRate = rng.uniform(0.3, 1.0);
            m_cylinders.push_back(std::move(c));
            m_frame.push_back(m_cylinders.back().base);
        }
    }

    const std::vector<TriangleMesh>& frame(int frame) override {
        const double t = frame * kFrameDt;
        for (std::size_t i = 0; i < m_cylinders.size(); ++i) {
            const Cylinder& c = m_cylinders[i];
            const double lo = std::min(c.bound, 0.5), hi = std::max(1.0 - c.bound, 0.5);
            const Eigen::Affine3d pose = Eigen::Translation3d(bounce(c.start, c.velocity, t, lo, hi)) *
                                         Eigen::AngleAxisd(c.spinRate * t, c.spinAxis) * c.orientation;
            const double twist = c.twistAmp * std::sin(c.twistFreq * kTwoPi * t + c.twistPhase);
            const double bend = c.bendAmp * std::sin(c.bendFreq * kTwoPi * t + c.bendPhase);
            const double bendDir = c.bendTurn * t + c.bendPhase;
            const Vec3 bendAxis(std::cos(bendDir), std::sin(bendDir), 0.0);
            const double pulsePhase = c.pulseFreq * kTwoPi * t + c.pulsePhase;
            std::vector<Vec3>& out = m_frame[i].vertices;
            for (std::size_t k = 0; k < c.base.vertices.size(); ++k) {
                const Vec3& p = c.base.vertices[k];
                const double s = p.z() / (0.5 * c.height);  // -1 .. 1 along the axis
                const double scale = 1.0 + c.pulseAmp * std::sin(c.pulseWaves * kPi * s + pulsePhase);
                const double a = twist * s;
                const double x = scale * p.x(), y = scale * p.y();
                Vec3 q(std::cos(a) * x - std::sin(a) * y, std::sin(a) * x + std::cos(a) * y, p.z());
                q += bendAxis * (bend * (s * s - 1.0 / 3.0));
                out[k] = pose * q;
            }
        }
        return m_frame;
    }

    std::string name() const override { return "env1-cylinders"; }

private:
    static constexpr double kDensity = 0.055;
    struct Cylinder {
        TriangleMesh base;
        double radius = 0, height = 0, bound = 0;
        double pulseAmp = 0, pulseFreq = 0, pulseWaves = 0, pulsePhase = 0;
        double bendAmp = 0, bendFreq = 0, bendPhase = 0, bendTurn = 0;
        double twistAmp = 0, twistFreq = 0, twistPhase = 0;
        Vec3 start = Vec3::Zero(), velocity = Vec3::Zero(), spinAxis = Vec3::UnitZ();
        Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
        double spinRate = 0;
    };
    std::vector<Cylinder> m_cylinders;
    std::vector<TriangleMesh> m_frame;
};

// ---------------------------------------------------------------------------------------------------------------
// Environment 2: deforming tori in a box.

class Env2 final : public Environment {
public:
    Env2(std::uint64_t seed, int count, int trianglesPerObject) {
        requireNonNegative(count, "env2 object count");
        Rng rng(seed ^ 0x656e76325f746f72ULL);
        // nu ~ 2 nv (the major circle is about twice the minor one), 2 nu nv ~ trianglesPerObject.
        const int nv = roundPositive(std::sqrt(std::max(trianglesPerObject, 18) / 4.0), 3);
        const int nu = roundPositive(std::max(trianglesPerObject, 18) / (2.0 * nv), 3);

        double totalVolume = 0.0;
        for (int i = 0; i < count; ++i) {
            Torus c;
            c.majorRadius = rng.uniform(0.8, 1.2);
            c.minorRadius = c.majorRadius * rng.uniform(0.42, 0.5);  // fat rings: more volume per extent
            c.base = makeTorus(c.majorRadius, c.minorRadius, nu, nv);
            c.nu = nu;
            c.nv = nv;
            c.waveAmp = rng.uniform(0.08, 0.15);
            c.waveNumber = rng.integer(2, 5);
            c.waveSpeed = rng.uniform(1.0, 3.0) * (rng.uniform() < 0.5 ? -1.0 : 1.0);
            c.wavePhase = rng.uniform(0.0, kTwoPi);
            c.warpAmp = rng.uniform(0.03, 0.08) * c.majorRadius;
            c.warpNumber = rng.integer(2, 3);
            c.warpSpeed = rng.uniform(0.5, 1.5);
            c.warpPhase = rng.uniform(0.0, kTwoPi);
            c.bound = c.majorRadius + c.minorRadius * (1.0 + c.waveAmp) + c.warpAmp;
            // Travelling waves keep the mean of (1 + A sin)^2 at 1 + A^2/2.
            totalVolume += signedVolume(c.base) * (1.0 + 0.5 * c.waveAmp * c.waveAmp);
            m_tori.push_back(std::move(c));
        }
        m_boxSize = count > 0 ? std::cbrt(totalVolume / kDensity) : 1.0;
        for (Torus& c : m_tori) {
            const double lo = std::min(c.bound, 0.5 * m_boxSize), hi = std::max(m_boxSize - c.bound, 0.5 * m_boxSize);
            c.start = rng.inBox(Vec3::Constant(lo), Vec3::Constant(hi));
            c.velocity = rng.unitVector() * (m_boxSize * rng.uniform(0.05, 0.12));
            c.orientation = rng.rotation();
            c.spinAxis = rng.unitVector();
            c.spinRate = rng.uniform(0.2, 0.6);
            m_frame.push_back(c.base);
        }
    }

    const std::vector<TriangleMesh>& frame(int frame) override {
        const double t = frame * kFrameDt;
        for (std::size_t i = 0; i < m_tori.size(); ++i) {
            const Torus& c = m_tori[i];
            const double lo = std::min(c.bound, 0.5 * m_boxSize), hi = std::max(m_boxSize - c.bound, 0.5 * m_boxSize);
            const Eigen::Affine3d pose = Eigen::Translation3d(bounce(c.start, c.velocity, t, lo, hi)) *
                                         Eigen::AngleAxisd(c.spinRate * t, c.spinAxis) * c.orientation;
            std::vector<Vec3>& out = m_frame[i].vertices;
            for (int a = 0; a < c.nu; ++a) {
                const double u = kTwoPi * a / c.nu;
                const double cu = std::cos(u), su = std::sin(u);
                // Travelling wave on the minor radius; a slower wave bends the ring out of its plane.
                const double r = c.minorRadius *
                                 (1.0 + c.waveAmp * std::sin(c.waveNumber * u - c.waveSpeed * t + c.wavePhase));
                const double lift = c.warpAmp * std::sin(c.warpNumber * u + c.warpSpeed * kTwoPi * t + c.warpPhase);
                for (int b = 0; b < c.nv; ++b) {
                    const double v = kTwoPi * b / c.nv;
                    const double rr = c.majorRadius + r * std::cos(v);
                    out[static_cast<std::size_t>(a * c.nv + b)] =
                        pose * Vec3(rr * cu, rr * su, r * std::sin(v) + lift);
                }
            }
        }
        return m_frame;
    }

    std::string name() const override { return "env2-tori"; }

private:
    static constexpr double kDensity = 0.07;
    struct Torus {
        TriangleMesh base;
        int nu = 3, nv = 3;
        double majorRadius = 1, minorRadius = 0.3, bound = 0;
        double waveAmp = 0, waveSpeed = 0, wavePhase = 0;
        int waveNumber = 0;
        double warpAmp = 0, warpSpeed = 0, warpPhase = 0;
        int warpNumber = 0;
        Vec3 start = Vec3::Zero(), velocity = Vec3::Zero(), spinAxis = Vec3::UnitZ();
        Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
        double spinRate = 0;
    };
    std::vector<Torus> m_tori;
    std::vector<TriangleMesh> m_frame;
    double m_boxSize = 1.0;
};

// ---------------------------------------------------------------------------------------------------------------
// Environment 3: bunny passing through the dragon.

/// Bunny stand-in: a lumpy sphere of ~75K triangles (2 * 274 * 137 = 75,076).
TriangleMesh makeLumpySphere() {
    TriangleMesh m = makeSphere(0.5, 274, 138);
    for (Vec3& p : m.vertices) {
        const Vec3 d = p.normalized();
        const double lumps = 1.0 + 0.12 * std::sin(3.0 * d.x() + 1.0) * std::sin(2.0 * d.y() + 0.5) +
                             0.08 * std::cos(5.0 * d.z() + 0.3 * d.x()) + 0.04 * std::sin(9.0 * d.y() - 2.0 * d.z());
        p = d * (0.5 * lumps);
    }
    return m;
}

/// Dragon stand-in: a bumpy tube around a (2,3) torus knot, ~20K triangles (2 * 12 * 833 = 19,992).
TriangleMesh makeBumpyKnot() {
    constexpr int around = 12;
    constexpr int along = 833;
    TriangleMesh m;
    m.vertices.reserve(static_cast<std::size_t>(around) * along);
    auto curve = [](double s) {
        return Vec3((2.0 + std::cos(3.0 * s)) * std::cos(2.0 * s), (2.0 + std::cos(3.0 * s)) * std::sin(2.0 * s),
                    std::sin(3.0 * s));
    };
    for (int j = 0; j < along; ++j) {
        const double s = kTwoPi * j / along;
        const double h = 1e-4;
        const Vec3 c = curve(s);
        const Vec3 tangent = (curve(s + h) - curve(s - h)).normalized();
        // The knot's tangent is never vertical, so z gives a well-defined frame all along the closed curve.
        const Vec3 binormal = tangent.cross(Vec3::UnitZ()).normalized();
        const Vec3 normal = binormal.cross(tangent);
        const double radius = 0.42 * (1.0 + 0.25 * std::sin(17.0 * s) * std::sin(5.0 * s + 1.0));
        for (int i = 0; i < around; ++i) {
            const double a = kTwoPi * i / around;
            const double bump = 1.0 + 0.1 * std::cos(3.0 * a + 7.0 * s);
            m.vertices.push_back(c + radius * bump * (std::cos(a) * normal + std::sin(a) * binormal));
        }
    }
    for (int j = 0; j < along; ++j) {
        const int j1 = (j + 1) % along;
        for (int i = 0; i < around; ++i) {
            const int i1 = (i + 1) % around;
            const auto id = [](int jj, int ii) { return static_cast<std::uint32_t>(jj * around + ii); };
            m.triangles.push_back({id(j, i), id(j1, i), id(j1, i1)});
            m.triangles.push_back({id(j, i), id(j1, i1), id(j, i1)});
        }
    }
    return m;
}

/// Reads `dir/file` when it exists; otherwise returns false (a present but malformed file throws ParseError).
bool tryRead(const std::string& dir, const char* file, TriangleMesh& out) {
    if (dir.empty()) return false;
    const std::filesystem::path path = std::filesystem::path(dir) / file;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return false;
    out = io::readMesh(path.string());
    return !out.triangles.empty();
}

class Env3 final : public Environment {
public:
    Env3(const std::string& dataDir, bool deformBunny, bool* usedStandIns) : m_deform(deformBunny) {
        bool bunnyStandIn = false, dragonStandIn = false;
        m_bunny = paperModel(dataDir, PaperModel::Bunny, &bunnyStandIn);
        m_dragon = paperModel(dataDir, PaperModel::Dragon, &dragonStandIn);
        const bool standIns = bunnyStandIn || dragonStandIn;
        normalize(m_bunny, kBunnySize);
        normalize(m_dragon, kDragonSize);
        if (usedStandIns != nullptr) *usedStandIns = standIns;
        m_frame = {m_bunny, m_dragon};
    }

    const std::vector<TriangleMesh>& frame(int frame) override {
        // One period of the path every kPeriod frames: the bunny swings through the dragon along x, with smaller
        // excursions in y and z; it stays within ~0.35 of the dragon's centre, so they overlap in most frames.
        const double phase = kTwoPi * frame / kPeriod;
        const Vec3 centre(0.35 * std::sin(phase), 0.08 * std::sin(2.0 * phase), 0.1 * std::cos(phase));
        const Eigen::Affine3d pose = Eigen::Translation3d(centre) *
                                     Eigen::AngleAxisd(0.6 * std::sin(phase), Vec3::UnitY()) *
                                     Eigen::AngleAxisd(0.25 * std::sin(3.0 * phase + 0.5), Vec3::UnitX());
        const double t = frame * kFrameDt;
        const double squash = 0.08 * std::sin(kTwoPi * 0.7 * t);
        const double twist = 0.35 * std::sin(kTwoPi * 0.4 * t + 1.0);
        std::vector<Vec3>& out = m_frame[0].vertices;
        for (std::size_t k = 0; k < m_bunny.vertices.size(); ++k) {
            Vec3 p = m_bunny.vertices[k];
            if (m_deform) {
                // Squash and stretch along y, a twist about y and a ripple travelling over the surface.
                p.y() *= 1.0 + squash;
                p.x() *= 1.0 - 0.5 * squash;
                p.z() *= 1.0 - 0.5 * squash;
                const double a = twist * p.y();
                p = Vec3(std::cos(a) * p.x() + std::sin(a) * p.z(), p.y(), -std::sin(a) * p.x() + std::cos(a) * p.z());
                p.x() += 0.02 * std::sin(12.0 * p.y() - kTwoPi * 1.3 * t);
                p.z() += 0.02 * std::sin(10.0 * p.x() + kTwoPi * 0.9 * t);
            }
            out[k] = pose * p;
        }
        return m_frame;
    }

    std::string name() const override { return m_deform ? "env3-bunny-dragon-deforming" : "env3-bunny-dragon"; }

private:
    static constexpr double kBunnySize = 0.8;
    static constexpr double kDragonSize = 1.0;
    static constexpr int kPeriod = 240;
    bool m_deform;
    TriangleMesh m_bunny, m_dragon;  // recentred and scaled, in their own frames
    std::vector<TriangleMesh> m_frame;
};

// ---------------------------------------------------------------------------------------------------------------
// Random scenes.

/// Closed box subdivided into n x n quads per face (12 n^2 triangles, watertight, outward-oriented).
TriangleMesh makeGridBox(const Vec3& halfExtents, int n) {
    TriangleMesh m;
    std::map<std::array<int, 3>, std::uint32_t> ids;
    auto vertex = [&](std::array<int, 3> c) {
        const auto it = ids.find(c);
        if (it != ids.end()) return it->second;
        const auto id = static_cast<std::uint32_t>(m.vertices.size());
        m.vertices.emplace_back(halfExtents.x() * (2.0 * c[0] / n - 1.0), halfExtents.y() * (2.0 * c[1] / n - 1.0),
                                halfExtents.z() * (2.0 * c[2] / n - 1.0));
        ids.emplace(c, id);
        return id;
    };
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;  // e_b x e_c = e_a
        for (int side = 0; side < 2; ++side) {
            for (int i = 0; i < n; ++i) {
                for (int j = 0; j < n; ++j) {
                    std::array<std::array<int, 3>, 4> q;
                    const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
                    for (int k = 0; k < 4; ++k) {
                        q[static_cast<std::size_t>(k)][static_cast<std::size_t>(a)] = side * n;
                        q[static_cast<std::size_t>(k)][static_cast<std::size_t>(b)] = i + di[k];
                        q[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)] = j + dj[k];
                    }
                    std::array<std::uint32_t, 4> v{vertex(q[0]), vertex(q[1]), vertex(q[2]), vertex(q[3])};
                    if (side == 1) {
                        m.triangles.push_back({v[0], v[1], v[2]});
                        m.triangles.push_back({v[0], v[2], v[3]});
                    } else {
                        m.triangles.push_back({v[0], v[2], v[1]});
                        m.triangles.push_back({v[0], v[3], v[2]});
                    }
                }
            }
        }
    }
    return m;
}

/// Random triangles around the origin within a cube of side `size`; about one in twelve is degenerate.
TriangleMesh makeSoup(Rng& rng, int triangles, double size) {
    TriangleMesh m;
    const double half = 0.5 * size, spread = 0.15 * size;
    for (int i = 0; i < triangles; ++i) {
        const Vec3 q = rng.inBox(Vec3::Constant(-half + spread), Vec3::Constant(half - spread));
        const auto base = static_cast<std::uint32_t>(m.vertices.size());
        const double kind = rng.uniform();
        if (kind < 0.03) {
            // A point: three equal vertices.
            m.vertices.insert(m.vertices.end(), {q, q, q});
            m.triangles.push_back({base, base + 1, base + 2});
        } else if (kind < 0.06) {
            // A segment: collinear vertices.
            const Vec3 d = rng.unitVector() * rng.uniform(0.2, 1.0) * spread;
            m.vertices.insert(m.vertices.end(), {q, q + d, q - 1.5 * d});
            m.triangles.push_back({base, base + 1, base + 2});
        } else if (kind < 0.08) {
            // A repeated index.
            const Vec3 d = rng.unitVector() * rng.uniform(0.2, 1.0) * spread;
            m.vertices.insert(m.vertices.end(), {q, q + d});
            m.triangles.push_back({base, base, base + 1});
        } else {
            for (int k = 0; k < 3; ++k) m.vertices.push_back(q + rng.unitVector() * rng.uniform(0.0, spread));
            m.triangles.push_back({base, base + 1, base + 2});
        }
    }
    return m;
}

}  // namespace

std::unique_ptr<Environment> makeEnv1(std::uint64_t seed, int count, int trianglesPerObject) {
    return std::make_unique<Env1>(seed, count, trianglesPerObject);
}

std::unique_ptr<Environment> makeEnv2(std::uint64_t seed, int count, int trianglesPerObject) {
    return std::make_unique<Env2>(seed, count, trianglesPerObject);
}

TriangleMesh paperModel(const std::string& dataDir, PaperModel model, bool* usedStandIn) {
    TriangleMesh mesh;
    bool standIn = false;
    switch (model) {
    case PaperModel::Bunny:
        if (!tryRead(dataDir, "bunny00.off", mesh)) mesh = makeLumpySphere(), standIn = true;
        break;
    case PaperModel::Dragon:
        if (!tryRead(dataDir, "ChineseDragon-10kv.off", mesh)) mesh = makeBumpyKnot(), standIn = true;
        break;
    case PaperModel::Armadillo:
        if (!tryRead(dataDir, "armadillo.off", mesh)) mesh = makeLumpySphere(), standIn = true;
        break;
    }
    if (usedStandIn != nullptr) *usedStandIn = standIn;
    return mesh;
}

std::unique_ptr<Environment> makeEnv3(const std::string& dataDir, bool deformBunny, bool* usedStandIns) {
    return std::make_unique<Env3>(dataDir, deformBunny, usedStandIns);
}

std::vector<TriangleMesh> makeRandomScene(std::uint64_t seed, const RandomSceneOptions& options) {
    requireNonNegative(options.objects, "random scene object count");
    if (!(options.boxSize > 0.0) || !std::isfinite(options.boxSize) || !(options.objectSize > 0.0) ||
        !std::isfinite(options.objectSize)) {
        throw std::invalid_argument("random scene boxSize and objectSize must be positive and finite");
    }
    Rng rng(seed ^ 0x72616e646f6d5343ULL);
    const int minT = std::max(1, std::min(options.minTriangles, options.maxTriangles));
    const int maxT = std::max(minT, options.maxTriangles);
    const int kinds = options.soups ? 5 : 3;  // sphere, box, torus [, open cylinder, soup]

    std::vector<TriangleMesh> scene;
    std::vector<Vec3> centres;
    scene.reserve(static_cast<std::size_t>(options.objects));
    for (int i = 0; i < options.objects; ++i) {
        const int target = rng.integer(minT, maxT);
        const double diameter = options.objectSize * rng.uniform(0.6, 1.4);
        const double radius = 0.5 * diameter;
        TriangleMesh m;
        switch (rng.integer(0, kinds - 1)) {
            case 0: {
                const int rows = roundPositive(std::sqrt(target / 4.0), 1);
                m = makeSphere(radius, roundPositive(target / (2.0 * rows), 3), rows + 1);
                break;
            }
            case 1: {
                const Vec3 half = Vec3(rng.uniform(0.4, 1.0), rng.uniform(0.4, 1.0), rng.uniform(0.4, 1.0)) * radius;
                m = makeGridBox(half, roundPositive(std::sqrt(target / 12.0), 1));
                break;
            }
            case 2: {
                const double minor = radius * rng.uniform(0.2, 0.35);
                const int nv = roundPositive(std::sqrt(target / 6.0), 3);
                m = makeTorus(radius - minor, minor, roundPositive(target / (2.0 * nv), 3), nv);
                break;
            }
            case 3: {
                const int segments = roundPositive(std::sqrt(target / 2.0), 3);
                m = makeOpenCylinder(radius * rng.uniform(0.2, 0.5), diameter * rng.uniform(0.6, 1.0), segments,
                                     roundPositive(target / (2.0 * segments), 1));
                break;
            }
            default:
                m = makeSoup(rng, target, diameter);
                break;
        }

        // Half of the objects are placed next to an earlier one, so that a fair fraction intersect.
        Vec3 centre;
        const double lo = std::min(radius, 0.5 * options.boxSize);
        const double hi = std::max(options.boxSize - radius, 0.5 * options.boxSize);
        if (!centres.empty() && rng.uniform() < 0.5) {
            const Vec3 near = centres[static_cast<std::size_t>(rng.integer(0, static_cast<int>(centres.size()) - 1))];
            centre = near + rng.unitVector() * (options.objectSize * rng.uniform(0.3, 0.9));
        } else {
            centre = rng.inBox(Vec3::Constant(lo), Vec3::Constant(hi));
        }
        centre = centre.cwiseMax(Vec3::Constant(lo)).cwiseMin(Vec3::Constant(hi));
        const Vec3 stretch(rng.uniform(0.8, 1.25), rng.uniform(0.8, 1.25), rng.uniform(0.8, 1.25));
        const Eigen::Affine3d pose = Eigen::Translation3d(centre) * rng.rotation() * Eigen::Scaling(stretch);
        transformMesh(m, pose);
        // Keep the whole object inside the box where it fits.
        const Aabb box = boundsOf(m);
        if (!box.isEmpty()) {
            Vec3 shift = Vec3::Zero();
            for (int k = 0; k < 3; ++k) {
                if (box.extent()[k] > options.boxSize) continue;
                if (box.min[k] < 0.0) shift[k] = -box.min[k];
                if (box.max[k] > options.boxSize) shift[k] = options.boxSize - box.max[k];
            }
            for (Vec3& p : m.vertices) p += shift;
            centre += shift;
        }
        centres.push_back(centre);
        scene.push_back(std::move(m));
    }
    return scene;
}

std::string defaultDataDir() {
    if (const char* env = std::getenv("CULLIDE_DATA_DIR"); env != nullptr && *env != '\0') return env;
#ifdef CULLIDE_SOURCE_DIR
    return std::string(CULLIDE_SOURCE_DIR) + "/data/meshes";
#else
    return "data/meshes";
#endif
}

}  // namespace cullide::scenes
