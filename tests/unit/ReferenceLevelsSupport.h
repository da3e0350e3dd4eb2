// The GPU culler's frame pipeline and levels on the CPU reference of the visibility test (ReferenceVisibility), and
// unit cubes to run it on: what the reference-level tests share.
#pragma once

#include "cullide/Culler.h"
#include "cullide/Settings.h"
#include "cullide/Types.h"

#include <memory>
#include <vector>

namespace cullide::test {

/// Settings that run every level (GpuLevels::Always) and no exact stage threshold.
Settings referenceLevels(Pipeline pipeline, Mode mode, int resolution);

/// The GPU culler with the reference pruning backend in place of the GL backend.
std::unique_ptr<Culler> referenceLevelsCuller(const Settings& s);

/// Unit cubes (12 triangles each) at the given corners.
std::vector<TriangleMesh> cubesAt(const std::vector<Vec3>& corners);

}  // namespace cullide::test
