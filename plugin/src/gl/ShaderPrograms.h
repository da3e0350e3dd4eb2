// The GL programs the culler and the snapshot renderer link, each as the embedded sources of its shaders (GLSL has no
// #include: a shader is "#version 450 core", bindings.h, then its pieces, in order). One table, read by GlProgram.cpp
// to compile them and by a test that validates every program with a second GLSL front end (glslangValidator). No GL
// here: the test needs no device.
#pragma once

#include <string>
#include <vector>

namespace cullide::gl {

enum class ShaderStage { Compute, Vertex, Fragment };

/// One shader of a program: its stage and the embedded sources that follow bindings.h.
struct ShaderPieces {
    ShaderStage stage;
    std::vector<const char*> pieces;
};

enum class Program {
    Cull,        ///< the compute back-end's pass 1 (with the packing of the alive items' records)
    Second,      ///< the compute back-end's pass 2
    Flag,        ///< the compute back-end's pass 3 and the iteration's end
    CullSetup,   ///< the raster back-end's set-up dispatch
    CullRaster,  ///< the raster back-end's passes (vertex and fragment)
    Survive,     ///< the raster back-end's survivor pass and the iteration's end
    Build,       ///< a level's boxes, footprints, bands and records
    Map,         ///< the mapped meshes' world positions
    GroupBoxes,  ///< the groups' boxes built on the device
    Start,       ///< a level described by its objects: its items, start and first view
    Exact,       ///< the device exact stage
    Snapshot,    ///< the snapshot renderer (vertex and fragment)
    Probe,       ///< measureGlLatency's dependent dispatch
};

struct ShaderProgram {
    Program id;
    const char* name;  ///< a file name stem, for tools
    const char* what;  ///< names the program in errors
    std::vector<ShaderPieces> shaders;
};

/// Every program, in the order of Program.
const std::vector<ShaderProgram>& shaderPrograms();
const ShaderProgram& shaderProgram(Program id);

/// Embedded shader sources (generated from shaders/ at build time); nullptr for an unknown name.
const char* shaderSource(const char* name);

/// The whole source of a shader as it is compiled. Throws std::logic_error for a piece that was not embedded.
std::string assembledSource(const ShaderPieces& shader);

}  // namespace cullide::gl
