#!/usr/bin/env bash
# Fuzzes the OFF, OBJ and scene readers with libFuzzer (clang, ASan + UBSan) for a bounded time.
#   scripts/fuzz.sh [SECONDS]   default 60; builds tests/fuzz in build-fuzz/ and runs it over a copy of the seed
#                               corpus (tests/fuzz/corpus). Exits non-zero on a crash, a sanitizer report, a hang
#                               (-timeout=10 s an input), an OOM (-rss_limit_mb=2048) or a leak; the input that did
#                               it is left in build-fuzz/fuzz-run/artifacts/ (add it to tests/fuzz/corpus once fixed).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
[[ "$seconds" =~ ^[0-9]+$ ]] || { echo "usage: scripts/fuzz.sh [seconds]" >&2; exit 2; }
scripts/deps.sh
dir=build-fuzz
source scripts/build_env.sh  # ccache (outside the clone) and Ninja
# Only the fuzz target and the cullide and cullide_io libraries (instrumented, see tests/fuzz/CMakeLists.txt) are
# built: a clang build of its own (the gcc trees' objects cannot serve). Warnings are not errors here: clang warns
# about things gcc (the warnings-as-errors builds) does not.
# shellcheck disable=SC2046  # the generator option is two words
CC=clang CXX=clang++ cmake -S . -B "$dir" $(cullide_generator_args "$dir") "${cullide_cmake_args[@]}" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_BUILD_FUZZ=ON -DCULLIDE_BUILD_BENCHMARKS=OFF \
  -DCULLIDE_BUILD_CGAL_ORACLE=OFF -DCULLIDE_WERROR=OFF >/dev/null
cmake --build "$dir" -j"$(nproc)" --target cullide_fuzz_readers
run="$dir/fuzz-run"
rm -rf "$run"
mkdir -p "$run/corpus" "$run/artifacts"
cp tests/fuzz/corpus/* "$run/corpus/"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
echo "fuzz: ${seconds} s over $(ls "$run/corpus" | wc -l) seed inputs"
"$dir/tests/fuzz/cullide_fuzz_readers" "$run/corpus" -dict=tests/fuzz/readers.dict -max_total_time="$seconds" \
  -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 -artifact_prefix="$run/artifacts/"
echo "fuzz: no finding in ${seconds} s"
