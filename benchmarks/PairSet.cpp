#include "PairSet.h"

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <utility>

namespace cullide::bench {

namespace {

constexpr std::uint32_t kMagic = 0x54524231;  // "TRB1"

template <class Key>
Comparison compareSorted(const std::vector<Key>& exact, const std::vector<Key>& reported) {
    Comparison c;
    c.expected = exact.size();
    c.reported = reported.size();
    std::size_t i = 0, j = 0;
    while (i < exact.size() && j < reported.size()) {
        if (exact[i] < reported[j]) {
            ++c.missed;
            ++i;
        } else if (reported[j] < exact[i]) {
            ++c.extra;
            ++j;
        } else {
            ++i;
            ++j;
        }
    }
    c.missed += exact.size() - i;
    c.extra += reported.size() - j;
    return c;
}

template <class T>
void sortUnique(std::vector<T>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
}

void put(std::ofstream& out, std::uint32_t v) { out.write(reinterpret_cast<const char*>(&v), sizeof v); }

std::uint32_t get(std::ifstream& in) {
    std::uint32_t v = 0;
    if (!in.read(reinterpret_cast<char*>(&v), sizeof v)) throw std::runtime_error("truth file truncated");
    return v;
}

}  // namespace

void PairSet::addTriangle(std::uint32_t a, std::uint32_t ta, std::uint32_t b, std::uint32_t tb) {
    if (a == b) return;
    if (b < a) {
        std::swap(a, b);
        std::swap(ta, tb);
    }
    m_triangles.push_back({a, ta, b, tb});
}

void PairSet::addObject(std::uint32_t a, std::uint32_t b) {
    if (a == b) return;
    if (b < a) std::swap(a, b);
    m_objects.push_back({a, b});
}

void PairSet::finish() {
    sortUnique(m_triangles);
    for (const TriangleKey& t : m_triangles) m_objects.push_back({t[0], t[2]});
    sortUnique(m_objects);
}

void PairSet::clear() {
    m_triangles.clear();
    m_objects.clear();
}

Comparison& Comparison::operator+=(const Comparison& o) {
    expected += o.expected;
    reported += o.reported;
    missed += o.missed;
    extra += o.extra;
    return *this;
}

Comparison compareTriangles(const std::vector<TriangleKey>& exact, const std::vector<TriangleKey>& reported) {
    return compareSorted(exact, reported);
}

Comparison compareObjects(const std::vector<ObjectKey>& exact, const std::vector<ObjectKey>& reported) {
    return compareSorted(exact, reported);
}

void writeTruth(const std::string& path, const Truth& truth) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + path);
    put(out, kMagic);
    put(out, static_cast<std::uint32_t>(truth.size()));
    for (const auto& [frame, set] : truth) {
        put(out, static_cast<std::uint32_t>(frame));
        put(out, static_cast<std::uint32_t>(set.objects().size()));
        for (const ObjectKey& o : set.objects()) {
            put(out, o[0]);
            put(out, o[1]);
        }
        put(out, static_cast<std::uint32_t>(set.triangles().size()));
        for (const TriangleKey& t : set.triangles())
            for (std::uint32_t v : t) put(out, v);
    }
    if (!out) throw std::runtime_error("error writing " + path);
}

Truth readTruth(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    if (get(in) != kMagic) throw std::runtime_error(path + ": not a truth file");
    Truth truth;
    const std::uint32_t frames = get(in);
    for (std::uint32_t k = 0; k < frames; ++k) {
        const int frame = static_cast<int>(get(in));
        PairSet set;
        const std::uint32_t objects = get(in);
        for (std::uint32_t i = 0; i < objects; ++i) {
            const std::uint32_t a = get(in);
            set.addObject(a, get(in));
        }
        const std::uint32_t triangles = get(in);
        for (std::uint32_t i = 0; i < triangles; ++i) {
            const std::uint32_t a = get(in), ta = get(in), b = get(in);
            set.addTriangle(a, ta, b, get(in));
        }
        set.finish();
        truth.emplace(frame, std::move(set));
    }
    return truth;
}

}  // namespace cullide::bench
