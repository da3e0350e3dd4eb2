// Mesh files on disk, shared by readMesh and the scene reader: what is wrong with a path (missing, a dangling
// link, a directory, ...), the mesh format named by its extension, and opening it.
#pragma once

#include <fstream>
#include <string>

namespace cullide::io::detail {

/// Why `path` cannot be read as a regular file, or "" when it can. Says what is actually wrong: missing, a dangling
/// link, a path the system cannot resolve (a symbolic-link loop, a name too long: the system's reason), a directory.
std::string fileProblem(const std::string& path);

/// The lower-case extension of `path`; `problem` says why it is not a mesh format that is read ("" when it is).
std::string checkedExtension(const std::string& path, std::string& problem);

/// Opens `path` (binary) or throws ParseError(path, 0, why).
void openForReading(const std::string& path, std::ifstream& in);

}  // namespace cullide::io::detail
