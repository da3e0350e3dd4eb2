#!/usr/bin/env bash
# Builds and runs the benchmarks (issue #5) and writes the report.
#   scripts/bench.sh            full run (~25 min on 2 cores + llvmpipe): out/bench/results.json, the plots and
#                               docs/benchmarks.md (with docs/bench/results-<cpu|gpu>.json and docs/bench/*.png)
#   scripts/bench.sh --quick    smoke run (~3 min): out/bench/results.json, out/bench/benchmarks.md, out/bench/plots/
# Both also run cullide-swap-bench (the two-line swap against Bullet's pipelines): out/bench/swap.{txt,json}.
# Each (scene, engine) runs as its own process (build-bench/benchmarks/cullide-bench-run), so its peak memory is its
# own; the list of runs is scripts/bench-runs.sh (shared with the GPU bundle, scripts/gpu-run.sh). The same command
# on a machine with an NVIDIA GPU picks the hardware EGL device (CULLIDE_GL_DEVICE overrides) and files its results
# as the "gpu" class next to the CPU-only ones.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
for a in "$@"; do
  case "$a" in
    --quick) quick=1 ;;
    *) echo "usage: scripts/bench.sh [--quick]" >&2; exit 2 ;;
  esac
done
t0=$(date +%s)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)

scripts/deps.sh >/dev/null
scripts/deps-bench
scripts/fetch_meshes.sh || true
dir=build-bench
cmake -S . -B $dir -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_WERROR=ON -DCULLIDE_BUILD_CGAL_ORACLE=OFF \
  -DCULLIDE_BUILD_TESTS=OFF >/dev/null
cmake --build $dir -j"$(nproc)" --target cullide-bench-run cullide-bench-report cullide-swap-bench >/dev/null
export MESA_SHADER_CACHE_DIR="$PWD/$dir/mesa-shader-cache"
run=$dir/benchmarks/cullide-bench-run
report=$dir/benchmarks/cullide-bench-report
t_built=$(date +%s)

out=out/bench
mkdir -p $out
echo "bench: $(( t_built - t0 )) s to build; running ($([ $quick -eq 1 ] && echo quick || echo full))"

probe=$($run --probe 2>/dev/null || echo '{"renderer":"","device":"none"}')
case "$probe" in
  *llvmpipe*|*softpipe*|*'"renderer":""'*) class=cpu ;;
  *) class=gpu ;;
esac
scripts/bench-runs.sh $run $out $([ $quick -eq 1 ] && echo --quick)
# The two-line swap against Bullet's default pipeline on typical scenes, in lockstep in one process (issue #12;
# docs/drop-in.md): a table on stdout, figures in swap.json.
$dir/benchmarks/cullide-swap-bench --steps $([ $quick -eq 1 ] && echo 20 || echo 120) --json $out/swap.json \
  2>$out/swap-lost.txt | tee $out/swap.txt

# Machine, then results.json and the report.
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
mesa=$(dpkg-query -W -f='${Version}' libgl1-mesa-dri 2>/dev/null || echo unknown)
driver=""
command -v nvidia-smi >/dev/null 2>&1 && driver=$(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | head -1)
esc() { printf '%s' "$1" | sed 's/\\/\\\\/g; s/"/\\"/g'; }
cat >$out/machine.json <<JSON
{"class": "$class", "quick": $([ $quick -eq 1 ] && echo true || echo false),
 "date": "$(date -u +%FT%TZ)", "cpu": "$(esc "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)")",
 "cores": $(nproc), "memory_gib": $(awk '/MemTotal/ {printf "%.1f", $2 / 1048576}' /proc/meminfo),
 "kernel": "$(uname -r)", "mesa_package": "$(esc "$mesa")", "nvidia": "$(esc "$driver")",
 "probe": $probe, "load_before": "$load_before", "load_after": "$load_after",
 "commit": "$(esc "${CULLIDE_BENCH_COMMIT:-$(git rev-parse --short HEAD 2>/dev/null || echo unknown)}")",
 "runtime_s": $(( $(date +%s) - t_built )), "build_s": $(( t_built - t0 ))}
JSON
$report combine --records $out/results.jsonl --machine $out/machine.json --out $out/results.json

if [ $quick -eq 1 ]; then
  docs=$out/benchmarks.md; plots=$out/plots; inputs=$out/results.json
else
  mkdir -p docs/bench
  cp $out/results.json docs/bench/results-$class.json
  docs=docs/benchmarks.md; plots=docs/bench; inputs=""
  for c in cpu gpu; do [ -f docs/bench/results-$c.json ] && inputs="$inputs docs/bench/results-$c.json"; done
fi
mkdir -p "$plots" $out/plotdata
# shellcheck disable=SC2086
$report render --docs "$docs" --plots "$plots" --data $out/plotdata $inputs
for gp in $out/plotdata/*.gp; do gnuplot "$gp"; done
echo "bench: done in $(( $(date +%s) - t0 )) s: $docs, $out/results.json"
[ -f $out/failures.txt ] && { echo "bench: failures:"; cat $out/failures.txt; }
exit 0
