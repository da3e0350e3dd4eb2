// Fuzzing: mutated mesh and scene files must parse (into valid meshes) or throw ParseError, nothing else.
#include "ReaderSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace cullide::io {
namespace {

using namespace cullide::test;

class Mutator {
public:
    explicit Mutator(std::uint64_t seed) : m_gen(seed) {}

    std::string mutate(std::string s) {
        const int rounds = 1 + static_cast<int>(below(4));
        for (int r = 0; r < rounds; ++r) {
            switch (below(10)) {
                case 0:  // random byte
                    if (!s.empty()) s[below(s.size())] = static_cast<char>(below(256));
                    break;
                case 1: {  // token from a dictionary of troublemakers
                    static const char* tokens[] = {"nan", "-1", "1e999", "4294967295", "1000000000000", "#", "\n",
                                                   "/", "//", "f ", "v ", "OFF", "0", "-0", "+", "3", " ", "\t",
                                                   "\r\n", "\"", "[", "]", "{", "}", ",", ":", "1e-400", "0x1",
                                                   "99999999999999999999999", "\xff"};
                    const std::string t = below(40) == 0 ? std::string(1, '\0') : tokens[below(std::size(tokens))];
                    s.insert(below(s.size() + 1), t);
                    break;
                }
                case 2:  // delete a range
                    if (!s.empty()) {
                        const std::size_t at = below(s.size());
                        s.erase(at, 1 + below(std::min<std::size_t>(16, s.size() - at)));
                    }
                    break;
                case 3:  // duplicate a range
                    if (!s.empty()) {
                        const std::size_t at = below(s.size());
                        const std::size_t len = 1 + below(std::min<std::size_t>(64, s.size() - at));
                        s.insert(below(s.size() + 1), s.substr(at, len));
                    }
                    break;
                case 4:  // truncate
                    s.resize(below(s.size() + 1));
                    break;
                case 5:  // change a digit
                case 6: {
                    for (int tries = 0; tries < 8 && !s.empty(); ++tries) {
                        const std::size_t at = below(s.size());
                        if (s[at] >= '0' && s[at] <= '9') {
                            s[at] = static_cast<char>('0' + below(10));
                            break;
                        }
                    }
                    break;
                }
                case 7: {  // swap two lines
                    std::vector<std::string> lines;
                    std::istringstream in(s);
                    for (std::string l; std::getline(in, l);) lines.push_back(l);
                    if (lines.size() >= 2) std::swap(lines[below(lines.size())], lines[below(lines.size())]);
                    s.clear();
                    for (const auto& l : lines) s += l + "\n";
                    break;
                }
                case 8:  // flip a bit
                    if (!s.empty()) s[below(s.size())] ^= static_cast<char>(1 << below(8));
                    break;
                default:  // random bytes
                    for (std::size_t k = 0, n = 1 + below(8); k < n; ++k) {
                        s.insert(below(s.size() + 1), 1, static_cast<char>(below(256)));
                    }
                    break;
            }
        }
        return s;
    }

private:
    std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(m_gen() % n); }
    std::mt19937_64 m_gen;
};

std::size_t lineCount(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')) + 1; }

void checkValid(const TriangleMesh& m) {
    for (const Vec3& p : m.vertices) ASSERT_TRUE(p.allFinite());
    for (const auto& t : m.triangles) {
        for (const auto i : t) ASSERT_LT(i, m.vertices.size());
    }
}

TEST(Fuzz, MutatedMeshFilesOnlyThrowParseError) {
    const std::string objBase =
        "# fuzz seed\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
        "f 1 2 3\nf 1/1 2/1 3/1 4/1\nf -1//1 -2//1 -3//1\nf 2/1/1 3/1/1 5/1/1\ng g\nusemtl m\n";
    const std::string offBase = kCubeOff + "# trailing comment\n";
    Mutator mutator(0xC0FFEE);
    const auto start = std::chrono::steady_clock::now();
    std::size_t parsed = 0, rejected = 0;
    for (int i = 0; i < 20000; ++i) {
        const bool isOff = (i % 2) == 0;
        const std::string input = mutator.mutate(isOff ? offBase : objBase);
        const std::string name = isOff ? "fuzz.off" : "fuzz.obj";
        try {
            std::istringstream in(input);
            const TriangleMesh m = isOff ? readOff(in, name) : readObj(in, name);
            checkValid(m);
            ++parsed;
        } catch (const ParseError& e) {
            ASSERT_EQ(e.file(), name);
            ASSERT_GE(e.line(), 1u) << e.what();
            ASSERT_LE(e.line(), lineCount(input) + 1) << e.what();
            ++rejected;
        } catch (const std::exception& e) {
            FAIL() << "input " << i << " threw a non-ParseError: " << e.what();
        }
        if (HasFatalFailure()) FAIL() << "input " << i;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RecordProperty("fuzz_seconds", std::to_string(seconds));
    // Both outcomes must occur, else the mutator tests nothing.
    EXPECT_GT(parsed, 500u);
    EXPECT_GT(rejected, 5000u);
}

TEST(Fuzz, MutatedSceneFilesOnlyThrowParseError) {
    TempDir dir;
    dir.write("a.off", kCubeOff);
    dir.write("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string base = R"({
  "objects": [
    {"mesh": "a.off", "transform": [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]},
    {"mesh": "b.obj"},
    {"mesh": "a.off", "transform": [0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 2, 0, 0, 0, 1]}
  ]
}
)";
    Mutator mutator(0xBADC0DE);
    std::size_t parsed = 0, rejected = 0;
    for (int i = 0; i < 1000; ++i) {
        const std::string input = mutator.mutate(base);
        const std::string path = dir.write("scene.json", input);
        try {
            const auto scene = readSceneFile(path);
            for (const auto& o : scene) checkValid(*o.mesh);
            ++parsed;
        } catch (const ParseError& e) {
            ASSERT_EQ(e.file(), path) << e.what();
            ASSERT_GE(e.line(), 1u) << e.what();
            ASSERT_LE(e.line(), lineCount(input) + 1) << e.what();
            ++rejected;
        } catch (const std::exception& e) {
            FAIL() << "input " << i << " threw a non-ParseError: " << e.what();
        }
        if (HasFatalFailure()) FAIL() << "input " << i;
    }
    EXPECT_GT(parsed, 25u);
    EXPECT_GT(rejected, 250u);
}

}  // namespace
}  // namespace cullide::io
