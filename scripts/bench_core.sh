#!/usr/bin/env bash
# Per-stage figures of the culler on the paper's environments (docs/performance.md). Writes out/bench/core.txt.
#   scripts/bench_core.sh [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-8}
scripts/deps.sh >/dev/null
scripts/fetch_meshes.sh || true
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target cullide-bench >/dev/null
mkdir -p out/bench
bench=build/benchmarks/cullide-bench
{
  echo "# $(date -u +%F) $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
  for scene in env1 env2 env3 env3-deform; do
    check=""
    [ "$scene" = env1 ] && check="--check"
    for config in "--gpu-levels auto" "--gpu-levels always" "--gpu-levels always --mode sampled" \
                  "--gpu-levels always --pipeline paper" "--gpu-levels always --resolution 64"; do
      echo "## $scene $config"
      $bench --scene "$scene" --frames "$frames" $config $check
    done
  done
} | tee out/bench/core.txt
