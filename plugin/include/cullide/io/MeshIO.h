// Mesh and scene file readers (OFF, OBJ, the cullide-pairs scene JSON). Malformed input throws ParseError with
// the file and line; readers never crash or hang on any input.
#pragma once

#include "cullide/Types.h"

#include <Eigen/Core>

#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide::io {

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
/// By extension (.off / .obj, case-insensitive).
TriangleMesh readMesh(const std::string& path);
void writeOff(const TriangleMesh& mesh, std::ostream& out);

struct SceneObject {
    std::string meshPath;                                   ///< as written in the scene file
    Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
    TriangleMesh mesh;                                      ///< loaded and transformed to world space
};

/// {"objects": [{"mesh": "a.off", "transform": [16 numbers, row-major 4x4]}, ...]}; mesh paths relative to the
/// scene file; transform optional (identity).
std::vector<SceneObject> readSceneFile(const std::string& path);

}  // namespace cullide::io
