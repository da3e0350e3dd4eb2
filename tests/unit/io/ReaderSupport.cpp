#include "ReaderSupport.h"

#include <unistd.h>

#include <exception>
#include <fstream>
#include <sstream>
#include <system_error>

namespace cullide::test {

using io::ParseError;

TempDir::TempDir() {
    static int counter = 0;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    m_path = fs::temp_directory_path() /
             ("cullide_io_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" +
              (info != nullptr ? std::string(info->name()) : std::string("x")));
    fs::remove_all(m_path);
    fs::create_directories(m_path);
}

TempDir::~TempDir() {
    std::error_code ec;
    fs::remove_all(m_path, ec);
}

std::string TempDir::write(const std::string& name, const std::string& content) const {
    const fs::path p = m_path / name;
    fs::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary);
    out << content;
    return p.string();
}

TriangleMesh off(const std::string& text) {
    std::istringstream in(text);
    return io::readOff(in, "test.off");
}

TriangleMesh obj(const std::string& text) {
    std::istringstream in(text);
    return io::readObj(in, "test.obj");
}

::testing::AssertionResult throwsAt(const std::function<void()>& f, std::size_t line, const std::string& file) {
    try {
        f();
    } catch (const ParseError& e) {
        if (e.line() != line) {
            return ::testing::AssertionFailure() << "ParseError at line " << e.line() << ", expected " << line
                                                 << ": " << e.what();
        }
        if (!file.empty() && e.file() != file) {
            return ::testing::AssertionFailure() << "ParseError names file '" << e.file() << "', expected '"
                                                 << file << "': " << e.what();
        }
        return ::testing::AssertionSuccess() << e.what();
    } catch (const std::exception& e) {
        return ::testing::AssertionFailure() << "threw a non-ParseError: " << e.what();
    }
    return ::testing::AssertionFailure() << "did not throw";
}

::testing::AssertionResult offFailsAt(const std::string& text, std::size_t line) {
    return throwsAt([&] { off(text); }, line, "test.off");
}

::testing::AssertionResult objFailsAt(const std::string& text, std::size_t line) {
    return throwsAt([&] { obj(text); }, line, "test.obj");
}

std::string messageOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const ParseError& e) {
        return e.what();
    }
    return "";
}

const std::string kCubeOff =
    "OFF\n"
    "# a unit cube with quad faces\n"
    "8 6 12\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
    "0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n";

}  // namespace cullide::test
