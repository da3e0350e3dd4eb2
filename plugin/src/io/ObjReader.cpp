// The OBJ reader: v and f records (faces in any of the four vertex forms, negative indices relative to the
// vertices read so far, forward references checked once every vertex is known); other records are skipped.
#include "io/TokenReader.h"

#include "cullide/io/MeshIO.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

namespace cullide::io {

namespace {

using detail::addFan;
using detail::kMaxVertices;
using detail::quote;
using detail::TokenReader;

bool isKeyword(std::string_view t) {
    auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
    if (t.empty() || !alpha(t[0])) return false;
    return std::all_of(t.begin(), t.end(), [&](char c) { return alpha(c) || (c >= '0' && c <= '9'); });
}

/// Faces that name a vertex defined further down (legal in OBJ): checked once all vertices are known.
struct PendingFace {
    std::size_t line;
    std::uint64_t maxIndex;
};

/// "v x y z [w | colour]".
Vec3 readObjVertex(TokenReader& r) {
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
        if (!r.next()) r.fail("vertex needs 3 coordinates, found " + std::to_string(k));
        p[k] = r.number("vertex coordinate");
    }
    bool allIntegers = true;
    r.trailingNumbers("vertex coordinates", allIntegers);
    return p;
}

/// One face vertex (v, v/vt, v//vn, v/vt/vn) as a 0-based index; `count` vertices are known so far.
std::int64_t readObjFaceVertex(const TokenReader& r, std::int64_t count) {
    const std::string_view ref = r.token();
    std::array<std::string_view, 3> parts{};
    std::size_t nParts = 0;
    std::size_t start = 0;
    while (true) {
        const std::size_t slash = ref.find('/', start);
        if (nParts == 3) r.fail("invalid face vertex " + quote(ref) + " (too many '/')");
        parts[nParts++] = ref.substr(start, slash == std::string_view::npos ? ref.npos : slash - start);
        if (slash == std::string_view::npos) break;
        start = slash + 1;
    }
    if (parts[0].empty()) r.fail("invalid face vertex " + quote(ref) + " (missing vertex index)");
    for (std::size_t p = 1; p < nParts; ++p) {
        if (parts[p].empty()) continue;
        if (r.integer(parts[p], "texture/normal index") == 0) {
            r.fail("invalid face vertex " + quote(ref) + " (index 0)");
        }
    }
    const std::int64_t v = r.integer(parts[0], "vertex index");
    if (v == 0) r.fail("vertex index 0 is invalid (OBJ indices start at 1)");
    if (v < 0) {
        if (count + v < 0) {
            r.fail("relative vertex index " + std::to_string(v) + " out of range (" + std::to_string(count) +
                   " vertices so far)");
        }
        return count + v;
    }
    if (static_cast<std::uint64_t>(v - 1) >= kMaxVertices) r.fail("vertex index " + std::to_string(v) + " out of range");
    return v - 1;
}

/// "f v1 v2 v3 ...", fanned into `mesh`; a face naming vertices not read yet goes to `pending`.
void readObjFace(TokenReader& r, std::vector<std::uint32_t>& polygon, TriangleMesh& mesh,
                 std::vector<PendingFace>& pending) {
    polygon.clear();
    std::uint64_t maxForward = 0;
    bool forward = false;
    const auto count = static_cast<std::int64_t>(mesh.vertices.size());
    while (r.next()) {
        const std::int64_t idx = readObjFaceVertex(r, count);
        if (idx >= count) {
            forward = true;
            maxForward = std::max(maxForward, static_cast<std::uint64_t>(idx));
        }
        polygon.push_back(static_cast<std::uint32_t>(idx));
    }
    if (polygon.size() < 3) {
        r.fail("face has " + std::to_string(polygon.size()) + " vertices (at least 3 are needed)");
    }
    if (forward) pending.push_back({r.line(), maxForward});
    addFan(mesh, polygon);
}

}  // namespace

TriangleMesh readObj(std::istream& in, const std::string& name) {
    TokenReader r(in, name);
    TriangleMesh mesh;
    std::vector<std::uint32_t> polygon;
    std::vector<PendingFace> pending;

    while (r.nextRecord()) {
        const std::string_view kw = r.token();
        if (kw == "v") {
            if (mesh.vertices.size() >= kMaxVertices) r.fail("too many vertices");
            mesh.vertices.push_back(readObjVertex(r));
        } else if (kw == "f") {
            readObjFace(r, polygon, mesh, pending);
        } else if (!isKeyword(kw)) {
            r.fail("unknown record " + quote(kw));
        }
        // Other records (vt, vn, g, o, s, usemtl, mtllib, l, ...) are ignored: nextRecord() skips their line.
    }

    for (const PendingFace& p : pending) {
        if (p.maxIndex >= mesh.vertices.size()) {
            throw ParseError(name, p.line,
                             "vertex index " + std::to_string(p.maxIndex + 1) + " out of range (" +
                                 std::to_string(mesh.vertices.size()) + " vertices)");
        }
    }
    return mesh;
}

}  // namespace cullide::io
