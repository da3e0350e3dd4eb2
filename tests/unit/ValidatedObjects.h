// Validated objects written by hand, for the tests that build a frame's state without validating meshes.
#pragma once

#include "FrameObjects.h"

namespace cullide::test {

/// A validated object with the fields these tests set.
inline ValidatedObject validated(bool valid, bool isMesh, const Aabb& box) {
    ValidatedObject v;
    v.valid = valid;
    v.isMesh = isMesh;
    v.box = box;
    return v;
}

}  // namespace cullide::test
