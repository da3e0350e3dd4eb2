#!/usr/bin/env bash
# Builds and runs the benchmarks (issue #5) and writes the report.
#   scripts/bench.sh            full run (~25 min on 2 cores + llvmpipe): out/bench/results.json, the plots and
#                               docs/benchmarks.md (with docs/bench/results-<cpu|gpu>.json and docs/bench/*.png)
#   scripts/bench.sh --quick    smoke run (~3 min): out/bench/results.json, out/bench/benchmarks.md, out/bench/plots/
# Each (scene, engine) runs as its own process (build-bench/benchmarks/cullide-bench-run), so its peak memory is its
# own. The same command on a machine with an NVIDIA GPU picks the hardware EGL device (CULLIDE_GL_DEVICE overrides)
# and files its results as the "gpu" class next to the CPU-only ones.
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
cmake --build $dir -j"$(nproc)" --target cullide-bench-run cullide-bench-report >/dev/null
export MESA_SHADER_CACHE_DIR="$PWD/$dir/mesa-shader-cache"
run=$dir/benchmarks/cullide-bench-run
report=$dir/benchmarks/cullide-bench-report
t_built=$(date +%s)

out=out/bench
mkdir -p $out/truth
rm -f $out/results.jsonl $out/truth/*.bin $out/failures.txt
echo "bench: $(( t_built - t0 )) s to build; running ($([ $quick -eq 1 ] && echo quick || echo full))"

# One record: bench TAG SCENE ENGINE FRAMES [more cullide-bench-run flags]. A failing run is listed, not fatal.
bench() {
  local tag=$1 scene=$2 engine=$3 frames=$4
  shift 4
  local t=$(date +%s)
  local rc=0
  timeout 900 $run --tag "$tag" --scene "$scene" --engine "$engine" --frames "$frames" --out $out/results.jsonl \
    "$@" 2>>$out/stderr.txt || rc=$?
  if [ $rc -ne 0 ]; then
    echo "$tag $scene $engine $* : exit $rc" | tee -a $out/failures.txt
  else
    printf '  %-12s %-12s %-16s %-28s %4d s\n' "$tag" "$scene" "$engine" "$*" $(( $(date +%s) - t ))
  fi
}

probe=$($run --probe 2>/dev/null || echo '{"renderer":"","device":"none"}')
case "$probe" in
  *llvmpipe*|*softpipe*|*'"renderer":""'*) class=cpu ;;
  *) class=gpu ;;
esac
has_engine() { $run --list-engines | grep -x "$1" >/dev/null; }
engines="exact cullide cullide-1t cullide-gpu cullide-sampled bullet-dbvt bullet-sap"
for e in fcl fcl-aabb; do has_engine $e && engines="$engines $e"; done
peers="bullet-dbvt bullet-sap"
for e in fcl fcl-aabb; do has_engine $e && peers="$peers $e"; done

if [ $quick -eq 1 ]; then
  side_scenes="env1:3 env3:1"
  steps=20
  sweep="env1:64:1 env1:256:1"
  objects="25 100 250"; tris="200 2000"; scale_frames=2
  scale_engines="cullide bullet-dbvt"
  breakable_steps=10; breakable_sample=5
else
  side_scenes="env1:20 env2:8 env3:8 env3-deform:8"
  steps=300
  # Every resolution of a scene on the same frames (error sums comparable along the sweep).
  sweep=""
  for r in 32 64 128 256 512 1024 2048; do sweep="$sweep env1:$r:3"; done
  for r in 32 64 128 256 512 1024 2048; do sweep="$sweep env3-deform:$r:2"; done
  objects="25 50 100 250 500 1000"; tris="200 1000 2000 5000 10000 20000"; scale_frames=5
  scale_engines="cullide cullide-gpu bullet-dbvt"
  breakable_steps=300; breakable_sample=30
fi
for e in fcl-aabb fcl; do has_engine $e && scale_engines="$scale_engines $e"; done

# 1. Side by side: the exact answer first (its truth file gives the others' errors), then every engine.
for sf in $side_scenes; do
  scene=${sf%%:*}; frames=${sf##*:}
  for e in $engines; do bench side "$scene" "$e" "$frames" --truth $out/truth/$scene.bin; done
done
for scene in stack landscape; do
  for e in cullide $peers; do
    case $e in fcl*) continue ;; esac
    bench side $scene $e $steps
  done
done
if $run --list-scenes | grep -x breakable >/dev/null; then
  for e in cullide cullide-fast bullet-dbvt bullet-sap; do
    bench side breakable $e $breakable_steps --sample-every $breakable_sample
  done
else
  echo "bench: the breakable scene is not built (no cullide_demo_scene target): no breakable rows" \
    | tee -a $out/failures.txt
fi

# 2. Speed against error: GPU levels forced, both modes, the side-by-side truth files.
for item in $sweep; do
  IFS=: read -r scene res frames <<<"$item"
  [ -f $out/truth/$scene.bin ] || bench side "$scene" exact 4 --truth $out/truth/$scene.bin
  for e in cullide-gpu cullide-sampled; do
    bench sweep "$scene" $e "$frames" --resolution "$res" --truth $out/truth/$scene.bin
  done
done

# 3. Scaling: objects (env1, 200 triangles each) and triangles per object (env2, 6 tori).
for n in $objects; do
  f=$scale_frames; [ "$n" -ge 1000 ] && f=3
  for e in $scale_engines; do bench scale-objects env1 $e $f --objects "$n"; done
done
for n in $tris; do
  for e in $scale_engines; do bench scale-triangles env2 $e $scale_frames --tris "$n"; done
done

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
