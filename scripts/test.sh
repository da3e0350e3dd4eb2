#!/usr/bin/env bash
# Installs what is missing, configures, builds and runs the tests.
#   scripts/test.sh                   release build (warnings as errors) in build/ and the whole suite: unit, GL (llvmpipe
#                                     or a GPU), the CGAL oracle, the Bullet adapter, the demo, the installed package
#   scripts/test.sh --sanitize        ASan + UBSan build in build-asan/ and the tests that exercise memory (see below)
#   scripts/test.sh --sanitize --all  the same build and every test it has
#   scripts/test.sh --bullet-double   the Bullet adapter and its tests against Debian's double-precision Bullet
# Compiles go through ccache, whose cache lives outside the clone, and new build trees use Ninja
# (scripts/build_env.sh); a second tree or a fresh clone of a commit built before recompiles nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() { echo "usage: scripts/test.sh [--sanitize [--all] | --bullet-double]" >&2; exit 2; }
mode=release
all=0
case "${1:-}" in
  "") ;;
  --sanitize) mode=sanitize ;;
  --bullet-double) mode=double ;;
  *) usage ;;
esac
if [ $# -ge 2 ]; then
  [ "$mode" = sanitize ] && [ "$2" = "--all" ] && [ $# -eq 2 ] || usage
  all=1
fi
scripts/deps.sh
scripts/fetch_meshes.sh  # the real bunny/dragon/armadillo for the tests that use them (exits 0 with a notice if not)
source scripts/build_env.sh
jobs=$(nproc)
configure() {  # configure DIR [CMAKE OPTIONS...]
  local dir=$1
  shift
  # shellcheck disable=SC2046  # the generator option is two words
  cmake -S . -B "$dir" $(cullide_generator_args "$dir") "${cullide_cmake_args[@]}" -DCULLIDE_WERROR=ON "$@"
  # Mesa's shader cache lives under the build dir so runs never depend on a warm home directory.
  export MESA_SHADER_CACHE_DIR="$PWD/$dir/mesa-shader-cache"
}
ctest_args=(--output-on-failure -j"$jobs" --timeout 600)

if [ $mode = double ]; then
  # Only the adapter's tests and what they link: the core libraries (cullide, cullide_io, cullide_scenes and the test
  # helpers) do not depend on Bullet and are compiled with build/'s flags, so ccache serves them from build/'s
  # compiles; the adapter, the demo scene and the tests are compiled again against BT_USE_DOUBLE_PRECISION.
  dir=build-f64
  configure $dir -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_BULLET_DOUBLE=ON -DCULLIDE_BUILD_CGAL_ORACLE=OFF
  cmake --build $dir -j"$jobs" --target cullide_bullet_tests
  # Known open deviation (issue #3): in the deeply interpenetrating 27-tori pile one pair-step penetrates deeper
  # than the culling margin and its deepest contact differs from GImpact's by 0.059 in double precision.
  ctest --test-dir $dir "${ctest_args[@]}" -L bullet -E 'BulletScale.GImpactTorusPile'
  exit 0
fi

if [ $mode = sanitize ]; then
  dir=build-asan
  # Debug semantics (assertions, KHR_debug) at -O1: unoptimised Eigen under ASan is ~10x slower, too slow for the
  # demo and Bullet scenes in the suite's time budget. The CGAL oracle is left out (slow there, and it tests
  # arithmetic, not memory); so are the benchmarks, which no test runs.
  configure $dir -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-g -O1" -DCULLIDE_SANITIZE=ON \
    -DCULLIDE_BUILD_CGAL_ORACLE=OFF -DCULLIDE_BUILD_BENCHMARKS=OFF
  # intercept_tls_get_addr=0: with it on, LeakSanitizer tracks the dynamic TLS of dlopen'ed libraries (Mesa's
  # driver) and, after a GL demo ran under -j2 load, its tracer read a stale entry of the main thread's DTLS at exit
  # and crashed ("DTLS 12 at 0x000000000e9c-0x001800002b9e", then "Tracer caught signal 11": GCC 12's libsanitizer
  # with glibc 2.36) — 1 run in 2-4 of ctest -R 'DemoScenes|EnvironmentLockstep' -j2. Off, 8 of 8 such runs passed
  # and leaks are still found (heap, stacks, static TLS are scanned; only the driver's dynamic TLS is not).
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:intercept_tls_get_addr=0"
  export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  if [ $all -eq 0 ]; then
    # The tests that exercise memory: every test of every label runs (unit, including the readers; bullet, the
    # adapter's parts and whole worlds; demo, fracture, the scenes and the long run; gl, the culler's GPU path against
    # the CPU reference) except the repetitions of one code path over more resolutions, settings or scenes, which
    # add time and no new code. Figures (ASan test seconds, 2 cores): the far-outlier sweep at 256-1024 px is 88 of
    # the suite's 467 s; env2/env3 in the GL lockstep, the pruning-strength table and the demo's scene run, and the
    # GL sweeps, another 50. What stays of each:
    #   FarOutliers: 16 and 64 px, both pipelines      EnvironmentLockstep: env1, every mode and backend
    #   VisibilityLockstep: every setting at 16 px     PruningStrength: env1, both pipelines
    #   DemoScenes: breakable, env1, env2              ReliableSweep (GL resolutions): none; the GL path runs in
    #                                                  GpuCuller, HardCases, the lockstep tests and CullidePairs
    # Each source area still runs under ASan + UBSan: plugin/ (CPU path, exact stage, GL backend), plugin's readers
    # (unit tests here, libFuzzer in scripts/fuzz.sh), scenes/, bullet_adapter/ (every bullet test), demos/ (the
    # demo tests and DemoLongRun). An exclusion that stops matching (a renamed test) only runs more.
    # (A parameterised test's name goes on with "  # GetParam() = ...": a name ends at ( |$).)
    skip=(
      'EveryResolution/FarOutliers\..*/(Auto|Paper)(256|512|1024)( |$)'
      'Frames/EnvironmentLockstep\..*/env[23]'
      'Matrix/VisibilityLockstep\..*/[A-Za-z]+64( |$)'
      'Environments/PruningStrength\..*/env[23]'
      'Scenes/DemoScenes\..*/env3( |$)'
      'Resolutions/ReliableSweep\.'
    )
    ctest_args+=(-E "$(IFS='|'; echo "${skip[*]}")")
  fi
else
  dir=build
  configure $dir -DCMAKE_BUILD_TYPE=RelWithDebInfo
fi
cmake --build $dir -j"$jobs"
ctest --test-dir $dir "${ctest_args[@]}"
