// The GL programs as the culler compiles them (ShaderPrograms.h), checked by a second GLSL front end: Khronos'
// reference compiler, glslangValidator, compiles and links each one as the desktop GLSL its "#version 450 core" line
// names. Mesa's compiler runs them in the GL tests; this holds them to the specification where drivers differ (an
// NVIDIA or AMD driver never meets them in CI). No GL device is needed.
#include "GlTestSupport.h"
#include "gl/ShaderPrograms.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <unistd.h>

namespace cullide::test {
namespace {

namespace fs = std::filesystem;
using gl::ShaderStage;

const char* extension(ShaderStage stage) {
    switch (stage) {
        case ShaderStage::Compute: return ".comp";
        case ShaderStage::Vertex: return ".vert";
        case ShaderStage::Fragment: return ".frag";
    }
    return "";
}

std::string readAll(const fs::path& path) {
    std::ifstream in(path);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

TEST(ShaderPrograms, EveryProgramCompilesAndLinksWithTheReferenceCompiler) {
    const std::string validator = CULLIDE_GLSLANG_VALIDATOR;
    if (validator.empty()) {
        if (runningInCi()) FAIL() << "glslangValidator not found at configure time (scripts/deps.sh installs it)";
        GTEST_SKIP() << "glslangValidator not found at configure time (Debian: glslang-tools)";
    }
    const fs::path dir = fs::temp_directory_path() / ("cullide-glsl-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    struct Removed {
        fs::path dir;
        ~Removed() {
            std::error_code ignored;
            fs::remove_all(dir, ignored);
        }
    } removed{dir};
    for (const gl::ShaderProgram& program : gl::shaderPrograms()) {
        std::string command = "'" + validator + "' -l";
        for (const gl::ShaderPieces& shader : program.shaders) {
            const fs::path file = dir / (std::string(program.name) + extension(shader.stage));
            std::ofstream(file) << gl::assembledSource(shader);
            command += " '" + file.string() + "'";
        }
        const fs::path log = dir / (std::string(program.name) + ".log");
        command += " > '" + log.string() + "' 2>&1";
        const int status = std::system(command.c_str());
        EXPECT_EQ(status, 0) << program.what << ":\n" << readAll(log);
    }
}

/// The table uses every stage file and every piece in shaders/, and each is embedded: a shader added there is
/// compiled, and validated above, only once a program lists it.
TEST(ShaderPrograms, TheTableUsesEveryShaderFile) {
    std::set<std::string> used;
    for (const gl::ShaderProgram& program : gl::shaderPrograms())
        for (const gl::ShaderPieces& shader : program.shaders) used.insert(shader.pieces.begin(), shader.pieces.end());
    std::size_t files = 0;
    for (const fs::directory_entry& entry : fs::directory_iterator(CULLIDE_SHADER_DIR)) {
        const std::string ext = entry.path().extension().string();
        if (ext != ".glsl" && ext != ".comp" && ext != ".vert" && ext != ".frag") continue;
        ++files;
        EXPECT_EQ(used.count(entry.path().filename().string()), 1u) << entry.path() << " is in no program";
        EXPECT_NE(gl::shaderSource(entry.path().filename().string().c_str()), nullptr)
            << entry.path() << " is not embedded (shaders/CMakeLists.txt)";
    }
    EXPECT_GE(files, used.size());
    for (const std::string& name : used) EXPECT_TRUE(fs::exists(fs::path(CULLIDE_SHADER_DIR) / name)) << name;
}

}  // namespace
}  // namespace cullide::test
