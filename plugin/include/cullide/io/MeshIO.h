// Mesh and scene file readers (OFF, OBJ, the cullide-pairs scene JSON). Malformed input throws ParseError with
// the file and line; readers never crash or hang on any input.
//
// Hostile input is handled in bounded time and memory: the mesh readers take tokens from the stream one at a time,
// only as many as the record being read needs, so they run in time linear in the bytes read and hold the mesh being
// built plus one token, whatever the length of a line (no line-length limit is needed: a valid face may list any
// number of vertices). Limits, far beyond any real file: a token (number, OBJ face vertex, keyword) is at most
// kMaxMeshTokenBytes; a scene file at most kMaxSceneFileBytes. Error messages are bounded: file names longer than
// 200 bytes and tokens longer than 32 are shortened, control bytes (NUL included) are shown escaped.
// Part of the cullide_io library (CMake: cullide::io; pkg-config: cullide-io), not of the culler.
#pragma once

#include "cullide/Types.h"

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide::io {

/// Longest token of a mesh file; comments and ignored OBJ records (names, materials) are skipped, never held.
inline constexpr std::size_t kMaxMeshTokenBytes = 4096;
/// Largest scene file (a scene lists mesh files and transforms, ~200 bytes an object, not geometry).
inline constexpr std::size_t kMaxSceneFileBytes = std::size_t(64) << 20;

class ParseError : public std::runtime_error {
public:
    ParseError(const std::string& file, std::size_t line, const std::string& message);
    const std::string& file() const { return m_file; }
    std::size_t line() const { return m_line; }  ///< 1-based; 0 when the error is not tied to a line
private:
    std::string m_file;
    std::size_t m_line;
};

/// OFF (with optional comments, "OFF" header, polygons fanned from their first vertex in file order).
TriangleMesh readOff(std::istream& in, const std::string& name);
/// OBJ: v and f records (f accepts v, v/vt, v//vn, v/vt/vn and negative indices); other records ignored.
TriangleMesh readObj(std::istream& in, const std::string& name);
/// By extension (.off / .obj, case-insensitive). A path that is missing, cannot be resolved (a symbolic-link loop,
/// a name too long: the system's reason), is not a regular file or contains a NUL byte is reported as such first.
TriangleMesh readMesh(const std::string& path);
void writeOff(const TriangleMesh& mesh, std::ostream& out);

struct SceneObject {
    std::string meshPath;                                   ///< as written in the scene file
    Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
    /// The mesh in its file's own frame, read once per file and shared by every object that references it (a
    /// scene that places one large mesh many times holds it once).
    std::shared_ptr<const TriangleMesh> mesh;
    /// `transform` as the culler takes it (Object::transform): world = linear · p + translation.
    Transform toWorld;
};

/// The object's mesh in world space, each vertex mapped by transformPoint(object.toWorld, ·) as the culler maps it.
TriangleMesh worldMesh(const SceneObject& object);

/// {"objects": [{"mesh": "a.off", "transform": [16 numbers, row-major 4x4]}, ...]}; mesh paths relative to the
/// scene file; transform optional (identity).
std::vector<SceneObject> readSceneFile(const std::string& path);
/// The same from a stream: `name` names the scene in errors, relative mesh paths are resolved against `baseDir`.
/// A mesh path containing a NUL byte is an error at its line.
std::vector<SceneObject> readScene(std::istream& in, const std::string& name, const std::filesystem::path& baseDir);

}  // namespace cullide::io
