// The cullide-pairs scene reader: a JSON list of mesh files and transforms. nlohmann::json checks the syntax;
// every semantic error (a missing or mistyped member, a non-affine or non-finite transform, a mesh that cannot be
// read) names the scene and the line of the offending value (found by JsonLocator). A mesh file named by several
// objects is read once and shared.
#include "io/JsonLocator.h"
#include "io/MeshFiles.h"
#include "io/ReaderText.h"

#include "cullide/io/MeshIO.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cullide::io {

namespace {

using detail::checkedExtension;
using detail::fileProblem;
using detail::JsonLocator;
using detail::kMaxShownName;
using detail::openForReading;
using detail::printable;

/// Longest mesh path a scene may name (PATH_MAX on Linux).
constexpr std::size_t kMaxPathBytes = 4096;

std::string stripJsonPrefix(const std::string& what) {
    // "[json.exception.parse_error.101] parse error at line 1, column 2: ..." -> "parse error at ...".
    if (!what.empty() && what[0] == '[') {
        const std::size_t close = what.find("] ");
        if (close != std::string::npos) return what.substr(close + 2);
    }
    return what;
}

std::string jsonTypeName(const nlohmann::json& j) { return j.type_name(); }

/// The whole scene text, at most kMaxSceneFileBytes.
std::string readSceneText(std::istream& in, const std::string& name) {
    std::string text;
    std::array<char, 1 << 16> chunk{};
    while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
        text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
        if (text.size() > kMaxSceneFileBytes) {
            throw ParseError(name, 0, "the scene is larger than " + std::to_string(kMaxSceneFileBytes >> 20) +
                                          " MiB (a scene lists mesh files and transforms, not geometry)");
        }
    }
    if (in.bad()) throw ParseError(name, 0, "read error");
    return text;
}

}  // namespace

std::vector<SceneObject> readSceneFile(const std::string& path) {
    std::ifstream in;
    openForReading(path, in);
    return readScene(in, path, std::filesystem::path(path).parent_path());
}

// `path` names the scene in errors (the file's path for readSceneFile).
std::vector<SceneObject> readScene(std::istream& in, const std::string& path, const std::filesystem::path& baseDir) {
    const std::string text = readSceneText(in, path);

    const JsonLocator loc(text);
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(text, nullptr, true, false);
    } catch (const nlohmann::json::parse_error& e) {
        const std::size_t line = e.byte > 0 ? loc.lineOf(static_cast<std::size_t>(e.byte - 1)) : 1;
        throw ParseError(path, line, "invalid JSON: " + stripJsonPrefix(e.what()));
    } catch (const nlohmann::json::exception& e) {
        const std::size_t at = loc.firstOverflowingNumber();
        throw ParseError(path, loc.lineOf(at), "invalid JSON: " + stripJsonPrefix(e.what()));
    }

    const std::size_t rootPos = loc.root();
    if (!doc.is_object()) {
        throw ParseError(path, loc.lineOf(rootPos),
                         "the scene must be a JSON object with an \"objects\" array, found " + jsonTypeName(doc));
    }
    const auto objectsIt = doc.find("objects");
    if (objectsIt == doc.end()) throw ParseError(path, loc.lineOf(rootPos), "missing the \"objects\" array");
    const std::size_t objectsPos = loc.member(rootPos, "objects");
    if (!objectsIt->is_array()) {
        throw ParseError(path, loc.lineOf(objectsPos),
                         "\"objects\" must be an array, found " + jsonTypeName(*objectsIt));
    }

    std::map<std::string, std::shared_ptr<const TriangleMesh>> cache;  // a mesh used by several objects: read once
    std::vector<SceneObject> scene;
    scene.reserve(objectsIt->size());
    for (std::size_t i = 0; i < objectsIt->size(); ++i) {
        const nlohmann::json& obj = (*objectsIt)[i];
        const std::size_t objPos = loc.element(objectsPos, i);
        const std::string where = "objects[" + std::to_string(i) + "]";
        if (!obj.is_object()) {
            throw ParseError(path, loc.lineOf(objPos), where + " must be an object, found " + jsonTypeName(obj));
        }
        SceneObject so;

        const auto meshIt = obj.find("mesh");
        if (meshIt == obj.end()) throw ParseError(path, loc.lineOf(objPos), where + " has no \"mesh\"");
        const std::size_t meshPos = loc.member(objPos, "mesh");
        if (!meshIt->is_string()) {
            throw ParseError(path, loc.lineOf(meshPos),
                             where + ".mesh must be a string, found " + jsonTypeName(*meshIt));
        }
        so.meshPath = meshIt->get<std::string>();
        if (so.meshPath.empty()) throw ParseError(path, loc.lineOf(meshPos), where + ".mesh is empty");
        if (so.meshPath.size() > kMaxPathBytes) {
            throw ParseError(path, loc.lineOf(meshPos),
                             where + ".mesh is " + std::to_string(so.meshPath.size()) + " bytes long (paths have at most " +
                                 std::to_string(kMaxPathBytes) + "): \"" + printable(so.meshPath, kMaxShownName) + "\"");
        }
        if (so.meshPath.find('\0') != std::string::npos) {
            throw ParseError(path, loc.lineOf(meshPos),
                             where + ".mesh contains a NUL byte (\\0): \"" + printable(so.meshPath, kMaxShownName) +
                                 "\"");
        }

        const auto trIt = obj.find("transform");
        const std::size_t trPos = trIt == obj.end() ? objPos : loc.member(objPos, "transform");
        if (trIt != obj.end()) {
            if (!trIt->is_array() || trIt->size() != 16) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform must be an array of 16 numbers (row-major 4x4)");
            }
            for (std::size_t k = 0; k < 16; ++k) {
                const nlohmann::json& v = (*trIt)[k];
                const std::size_t vPos = loc.element(trPos, k);
                if (!v.is_number()) {
                    throw ParseError(path, loc.lineOf(vPos),
                                     where + ".transform[" + std::to_string(k) + "] must be a number, found " +
                                         jsonTypeName(v));
                }
                const double d = v.get<double>();
                if (!std::isfinite(d)) {
                    throw ParseError(path, loc.lineOf(vPos),
                                     where + ".transform[" + std::to_string(k) + "] is not finite");
                }
                so.transform(static_cast<Eigen::Index>(k / 4), static_cast<Eigen::Index>(k % 4)) = d;
            }
            if (so.transform.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform is not affine (its last row must be 0 0 0 1)");
            }
        }

        std::filesystem::path meshFile(so.meshPath);
        if (meshFile.is_relative()) meshFile = baseDir / meshFile;
        const std::string meshFileName = meshFile.string();
        auto cached = cache.find(meshFileName);
        if (cached == cache.end()) {
            // Problems with the reference itself are reported at the scene's line (names shown shortened).
            std::string problem = fileProblem(meshFileName);
            if (problem.empty()) checkedExtension(meshFileName, problem);
            if (!problem.empty()) {
                throw ParseError(path, loc.lineOf(meshPos),
                                 where + ".mesh: " + problem + ": " + printable(meshFileName, kMaxShownName));
            }
            // Errors inside the mesh name the mesh file and its line.
            cached = cache.emplace(meshFileName, std::make_shared<const TriangleMesh>(readMesh(meshFileName))).first;
        }
        so.mesh = cached->second;
        so.toWorld.linear = so.transform.topLeftCorner<3, 3>();
        so.toWorld.translation = so.transform.topRightCorner<3, 1>();

        // Every vertex must land on a finite point (checked, not stored: the culler maps them itself).
        for (std::size_t v = 0; v < so.mesh->vertices.size(); ++v) {
            if (!transformPoint(so.toWorld, so.mesh->vertices[v]).allFinite()) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform maps vertex " + std::to_string(v) + " of " + so.meshPath +
                                     " to a non-finite point");
            }
        }
        scene.push_back(std::move(so));
    }
    return scene;
}

TriangleMesh worldMesh(const SceneObject& object) {
    TriangleMesh world;
    if (object.mesh == nullptr) return world;
    world.triangles = object.mesh->triangles;
    world.vertices.reserve(object.mesh->vertices.size());
    for (const Vec3& p : object.mesh->vertices) world.vertices.push_back(transformPoint(object.toWorld, p));
    return world;
}

}  // namespace cullide::io
