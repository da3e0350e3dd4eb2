// Mesh files on disk (MeshFiles.h) and readMesh, which picks the reader by the file's extension.
#include "io/MeshFiles.h"

#include "io/ReaderText.h"

#include "cullide/io/MeshIO.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

namespace cullide::io {

namespace detail {

namespace {

std::string lowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](char c) {
        return static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    });
    return ext;
}

}  // namespace

std::string fileProblem(const std::string& path) {
    if (path.empty()) return "empty path";
    if (path.find('\0') != std::string::npos) return "the path contains a NUL byte (\\0)";
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (status.type() == std::filesystem::file_type::not_found) {
        std::error_code linkEc;
        if (std::filesystem::is_symlink(std::filesystem::symlink_status(path, linkEc))) {
            return "dangling symbolic link (its target does not exist)";
        }
        return "file does not exist";
    }
    if (ec) return "cannot resolve the path: " + ec.message();
    if (std::filesystem::is_directory(status)) return "a directory, not a file";
    if (!std::filesystem::is_regular_file(status)) return "not a regular file";
    return "";
}

std::string checkedExtension(const std::string& path, std::string& problem) {
    const std::string ext = lowerExtension(path);
    problem.clear();
    if (ext != ".off" && ext != ".obj") {
        problem = "unsupported mesh format '" + printable(ext, 32) + "' (.off and .obj are read)";
    }
    return ext;
}

void openForReading(const std::string& path, std::ifstream& in) {
    if (const std::string problem = fileProblem(path); !problem.empty()) throw ParseError(path, 0, problem);
    in.open(path, std::ios::binary);
    if (!in) throw ParseError(path, 0, "cannot open the file for reading");
}

}  // namespace detail

TriangleMesh readMesh(const std::string& path) {
    // The file first: a missing file is reported as missing whatever its name.
    if (const std::string problem = detail::fileProblem(path); !problem.empty()) throw ParseError(path, 0, problem);
    std::string problem;
    const std::string ext = detail::checkedExtension(path, problem);
    if (!problem.empty()) throw ParseError(path, 0, problem);
    std::ifstream in;
    detail::openForReading(path, in);
    return ext == ".off" ? readOff(in, path) : readObj(in, path);
}

}  // namespace cullide::io
