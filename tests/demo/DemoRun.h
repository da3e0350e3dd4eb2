// Running cullide-demo from a test: its exit status, its output files, a fresh directory per run, and the project's
// GL test policy for a demo that reports "no GL" (exit 3).
#pragma once

#include "GlTestSupport.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace cullide::test {

/// Runs cullide-demo with `args`; returns its exit status. Output goes to `log`.
int runDemo(const std::string& args, const std::filesystem::path& log);

/// The whole content of file p.
std::string slurp(const std::filesystem::path& p);

/// An empty directory under the test's temporary directory.
std::filesystem::path freshDir(const std::string& name);

}  // namespace cullide::test

/// Skips outside CI / fails in CI when the demo reports "no GL" (exit 3), per the project's GL test policy.
#define SKIP_IF_NO_GL(status, log)                                                                           \
    do {                                                                                                     \
        if ((status) == 3) {                                                                                 \
            if (::cullide::test::runningInCi()) FAIL() << "CI=true but no GL: " << ::cullide::test::slurp(log); \
            GTEST_SKIP() << "no EGL/GL device here (outside CI): " << ::cullide::test::slurp(log);           \
        }                                                                                                    \
    } while (false)
