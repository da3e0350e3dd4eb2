// GL test policy: a GL test may skip (with a clear message) only outside CI when no EGL device exists; with
// CI=true a missing EGL device fails the test, so a suite that skipped everything can never pass.
#pragma once

#include "cullide/Culler.h"
#include "cullide/io/Snapshot.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace cullide::test {

bool runningInCi();

/// Creates the GPU culler or explains why not; returns nullptr after recording a skip or failure.
std::unique_ptr<Culler> makeGpuCuller(const Settings& settings, std::string& whyNot);

/// Creates the snapshot renderer (device from env CULLIDE_GL_DEVICE) or explains why not; nullptr without GL.
std::unique_ptr<SnapshotRenderer> makeSnapshotRenderer(std::string& whyNot);

}  // namespace cullide::test

/// Use at the top of a GL test body: `CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);` declares `culler`.
#define CULLIDE_GPU_CULLER_OR_SKIP(var, settings)                                          \
    std::unique_ptr<::cullide::Culler> var;                                                \
    do {                                                                                    \
        std::string whyNot_;                                                                \
        var = ::cullide::test::makeGpuCuller((settings), whyNot_);                          \
        if (!var) {                                                                         \
            if (::cullide::test::runningInCi()) {                                           \
                ADD_FAILURE() << "CI=true but no usable GL: " << whyNot_;                   \
                return;                                                                     \
            }                                                                               \
            GTEST_SKIP() << "no EGL/GL device here (outside CI): " << whyNot_;              \
        }                                                                                   \
    } while (false)

/// The same policy for the snapshot renderer: `CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);` declares `renderer`.
#define CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(var)                                             \
    std::unique_ptr<::cullide::SnapshotRenderer> var;                                      \
    do {                                                                                    \
        std::string whyNot_;                                                                \
        var = ::cullide::test::makeSnapshotRenderer(whyNot_);                               \
        if (!var) {                                                                         \
            if (::cullide::test::runningInCi()) {                                           \
                ADD_FAILURE() << "CI=true but no usable GL: " << whyNot_;                   \
                return;                                                                     \
            }                                                                               \
            GTEST_SKIP() << "no EGL/GL device here (outside CI): " << whyNot_;              \
        }                                                                                   \
    } while (false)
