// What the reader tests share: a temporary directory per test, the OFF and OBJ readers on strings, expectations of
// a ParseError at a given line, and a cube as an OFF file.
#pragma once

#include "cullide/io/MeshIO.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>

namespace cullide::test {

namespace fs = std::filesystem;

/// A fresh temporary directory per test, removed afterwards.
class TempDir {
public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    std::string write(const std::string& name, const std::string& content) const;
    const fs::path& path() const { return m_path; }

private:
    fs::path m_path;
};

/// readOff / readObj of `text`, as the file test.off / test.obj.
TriangleMesh off(const std::string& text);
TriangleMesh obj(const std::string& text);

/// Runs `f`, expects a ParseError at `line` naming `file`; returns its message for further checks.
::testing::AssertionResult throwsAt(const std::function<void()>& f, std::size_t line, const std::string& file = "");
::testing::AssertionResult offFailsAt(const std::string& text, std::size_t line);
::testing::AssertionResult objFailsAt(const std::string& text, std::size_t line);

/// The message of the ParseError that `f` throws; empty if it throws none.
std::string messageOf(const std::function<void()>& f);

/// A unit cube with quad faces.
extern const std::string kCubeOff;

}  // namespace cullide::test
