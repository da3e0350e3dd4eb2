#include "gl/ShaderPrograms.h"

#include <stdexcept>

namespace cullide::gl {

const std::vector<ShaderProgram>& shaderPrograms() {
    using S = ShaderStage;
    static const std::vector<ShaderProgram> programs = {
        {Program::Cull, "cull", "the visibility program",
         {{S::Compute, {"view.glsl", "common.glsl", "visit.glsl", "passes.glsl", "pack.glsl", "scan.glsl",
                        "cull.comp"}}}},
        {Program::Second, "second", "the second pass program",
         {{S::Compute, {"view.glsl", "common.glsl", "visit.glsl", "passes.glsl", "scan.glsl", "second.comp"}}}},
        {Program::Flag, "flag", "the flag pass program",
         {{S::Compute, {"view.glsl", "common.glsl", "visit.glsl", "passes.glsl", "gather.glsl", "iteration.glsl",
                        "scan.glsl", "flag.comp"}}}},
        {Program::CullSetup, "cull_setup", "the visibility setup program",
         {{S::Compute, {"view.glsl", "common.glsl", "records.glsl", "cull_setup.comp"}}}},
        {Program::CullRaster, "cull_raster", "the visibility raster program",
         {{S::Vertex, {"view.glsl", "common.glsl", "records.glsl", "cull.vert"}},
          {S::Fragment, {"view.glsl", "common.glsl", "visit.glsl", "records.glsl", "cull.frag"}}}},
        {Program::Survive, "survive", "the survivor program",
         {{S::Compute, {"view.glsl", "common.glsl", "visit.glsl", "passes.glsl", "gather.glsl", "iteration.glsl",
                        "pack.glsl", "survive.comp"}}}},
        {Program::Build, "build", "the record build program",
         {{S::Compute, {"view.glsl", "passes.glsl", "geometry.glsl", "build.comp"}}}},
        {Program::Map, "map", "the mapped meshes' program", {{S::Compute, {"map.comp"}}}},
        {Program::GroupBoxes, "group_boxes", "the group boxes program", {{S::Compute, {"group_boxes.comp"}}}},
        {Program::Start, "start", "the level start program",
         {{S::Compute, {"view.glsl", "passes.glsl", "geometry.glsl", "ranges.glsl", "gather.glsl", "start.comp"}}}},
        {Program::Exact, "exact", "the exact stage program",
         {{S::Compute, {"geometry.glsl", "ranges.glsl", "exact.comp"}}}},
        {Program::Snapshot, "snapshot", "the snapshot program",
         {{S::Vertex, {"snapshot.vert"}}, {S::Fragment, {"snapshot.frag"}}}},
        {Program::Probe, "probe", "the latency probe's program", {{S::Compute, {"probe.comp"}}}},
    };
    return programs;
}

const ShaderProgram& shaderProgram(Program id) {
    for (const ShaderProgram& p : shaderPrograms())
        if (p.id == id) return p;
    throw std::logic_error("cullide: a shader program missing from the table");
}

std::string assembledSource(const ShaderPieces& shader) {
    std::string text = "#version 450 core\n";
    const auto append = [&](const char* name) {
        const char* piece = shaderSource(name);
        if (piece == nullptr) throw std::logic_error(std::string("missing embedded shader ") + name);
        text += piece;
        text += '\n';
    };
    append("bindings.h");
    for (const char* name : shader.pieces) append(name);
    return text;
}

}  // namespace cullide::gl
