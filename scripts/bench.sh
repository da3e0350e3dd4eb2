#!/usr/bin/env bash
# Builds and runs the benchmarks and writes the pages generated from their results.
#   scripts/bench.sh            full run (~8 min on 2 cores + llvmpipe): docs/benchmarks.md (from
#                               docs/bench/results-<cpu|gpu>.json, plots docs/bench/*.png), docs/swap.md (from
#                               docs/bench/swap-<cpu|gpu>.json) and the README's headline table
#   scripts/bench.sh --swap     the two-line swap's runs only: docs/swap.md and the README's headline table
#   scripts/bench.sh --quick    smoke run (~3 min) into out/bench/ only: results.json, benchmarks.md, swap.md, plots/
# Each (scene, engine) of the culler's benchmarks runs as its own process (build-bench/benchmarks/cullide-bench-run),
# so its peak memory is its own; the list of runs is scripts/bench-runs.sh (shared with the GPU bundle,
# scripts/gpu-run.sh). cullide-swap-bench steps Bullet's two pipelines and the two-line swap in lockstep, once with
# the default switches and once per set of culling switches (SWAP_STEPS steps: default 120, 20 with --quick). The
# same command on a machine with an NVIDIA GPU picks the hardware EGL device (CULLIDE_GL_DEVICE overrides) and files
# its results as the "gpu" class next to the CPU-only ones.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
swap_only=0
for a in "$@"; do
  case "$a" in
    --quick) quick=1 ;;
    --swap) swap_only=1 ;;
    *) echo "usage: scripts/bench.sh [--quick] [--swap]" >&2; exit 2 ;;
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
echo "bench: $(( t_built - t0 )) s to build; running ($([ $quick -eq 1 ] && echo quick || echo full)$(
  [ $swap_only -eq 1 ] && echo ', the swap only'))"

probe=$($run --probe 2>/dev/null || echo '{"renderer":"","device":"none"}')
case "$probe" in
  *llvmpipe*|*softpipe*|*'"renderer":""'*) class=cpu ;;
  *) class=gpu ;;
esac
[ $swap_only -eq 1 ] || scripts/bench-runs.sh $run $out $([ $quick -eq 1 ] && echo --quick)

# The two-line swap against Bullet's default pipeline and btAxisSweep3, in lockstep in one process (docs/swap.md):
# one run per set of switches (SWITCHES: cullide-swap-bench flags, NAME=VALUE for an environment switch), each a table
# on stdout and its rows in swap-NAME.json.
swap_steps=${SWAP_STEPS:-$([ $quick -eq 1 ] && echo 20 || echo 120)}
swap_runs=()
run_swap() {  # run_swap NAME "SWITCHES" [--scene S]...
  local name=$1 switches=$2
  shift 2
  local envs=() flags=() w
  for w in $switches; do
    case "$w" in *=*) envs+=("$w") ;; *) flags+=("$w") ;; esac
  done
  echo "bench: cullide-swap-bench ${switches:-(default switches)} $*"
  env ${envs[@]+"${envs[@]}"} $dir/benchmarks/cullide-swap-bench --steps "$swap_steps" ${flags[@]+"${flags[@]}"} "$@" \
    --json "$out/swap-$name.json" 2>"$out/swap-$name-lost.txt" | tee "$out/swap-$name.txt"
  swap_runs+=(--run "$switches" "$out/swap-$name.json")
}
run_swap defaults ""
gimpact_scenes=""
for s in tori-pile gimpact-landscape small-units tori-plane gimpact-demo env1-world env2-world env3-world \
         env3-deform-world breakable; do
  gimpact_scenes="$gimpact_scenes --scene $s"
done
# Every switch On, every scene: the culled path's cost and its contact error against Bullet's (lost pairs must be 0).
run_swap every-switch-on "--culling on"
# Auto trialled on this machine too (it trials only with a hardware GL device by default): what it decides here.
# shellcheck disable=SC2086
run_swap auto-anywhere "--auto-culling-anywhere" $gimpact_scenes --scene landscape-hulls

# Machine, then the results files and the pages.
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
$report swap-combine --machine $out/machine.json --out $out/swap-results.json "${swap_runs[@]}"
[ $swap_only -eq 1 ] || $report combine --records $out/results.jsonl --machine $out/machine.json --out $out/results.json

if [ $quick -eq 1 ]; then
  $report swap --docs $out/swap.md $out/swap-results.json
  docs=$out/benchmarks.md; plots=$out/plots; inputs=$out/results.json
else
  mkdir -p docs/bench
  cp $out/swap-results.json docs/bench/swap-$class.json
  swaps=()
  for c in cpu gpu; do [ -f docs/bench/swap-$c.json ] && swaps+=("docs/bench/swap-$c.json"); done
  $report swap --docs docs/swap.md "${swaps[@]}"
  [ $swap_only -eq 1 ] || cp $out/results.json docs/bench/results-$class.json
  docs=docs/benchmarks.md; plots=docs/bench; inputs=""
  for c in cpu gpu; do [ -f docs/bench/results-$c.json ] && inputs="$inputs docs/bench/results-$c.json"; done
  swap_args=()
  for s in "${swaps[@]}"; do swap_args+=(--swap "$s"); done
  # shellcheck disable=SC2086
  $report headline --readme README.md "${swap_args[@]}" $inputs
fi
if [ $swap_only -eq 0 ]; then
  mkdir -p "$plots" $out/plotdata
  # shellcheck disable=SC2086
  $report render --docs "$docs" --plots "$plots" --data $out/plotdata $inputs
  for gp in $out/plotdata/*.gp; do gnuplot "$gp"; done
fi
echo "bench: done in $(( $(date +%s) - t0 )) s: $([ $swap_only -eq 1 ] || echo "$docs, ")$(
  [ $quick -eq 1 ] && echo $out/swap.md || echo docs/swap.md, README.md)"
[ -f $out/failures.txt ] && [ $swap_only -eq 0 ] && { echo "bench: failures:"; cat $out/failures.txt; }
exit 0
