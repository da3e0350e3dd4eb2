#!/usr/bin/env bash
# The benchmark run list (issue #5), shared by scripts/bench.sh and the GPU bundle's run.sh (scripts/gpu-run.sh):
#   scripts/bench-runs.sh RUN OUT [--quick]
# RUN is cullide-bench-run; OUT gets results.jsonl (one record per run), truth/*.bin (the exact answers the other
# engines' errors are measured against), failures.txt (failing runs; a failing run is listed, not fatal) and
# stderr.txt. Each (scene, engine) runs as its own process, so its peak memory is its own.
# Environment: BENCH_RUN_TIMEOUT (seconds per run, default 900); BENCH_SWEEP_RESOLUTIONS (the resolution sweep's
# resolutions, default 32 ... 2048; the GPU bundle adds 4096 on hardware devices); BENCH_DEADLINE (epoch seconds,
# optional): runs that would start after it are skipped and listed in failures.txt, so a time-limited caller still
# gets a report.
set -euo pipefail
usage() { echo "usage: scripts/bench-runs.sh RUN OUT [--quick]" >&2; exit 2; }
[ $# -ge 2 ] || usage
run=$1 out=$2
shift 2
quick=0
for a in "$@"; do
  case "$a" in
    --quick) quick=1 ;;
    *) usage ;;
  esac
done
run_timeout=${BENCH_RUN_TIMEOUT:-900}
deadline=${BENCH_DEADLINE:-}

mkdir -p "$out/truth"
rm -f "$out/results.jsonl" "$out"/truth/*.bin "$out/failures.txt"

# One record: bench TAG SCENE ENGINE FRAMES [more cullide-bench-run flags]. A failing run is listed, not fatal.
bench() {
  local tag=$1 scene=$2 engine=$3 frames=$4
  shift 4
  local t=$(date +%s)
  local rc=0
  if [ -n "$deadline" ] && [ "$t" -ge "$deadline" ]; then
    echo "$tag $scene $engine $* : skipped (time budget spent)" | tee -a "$out/failures.txt"
    return 0
  fi
  timeout "$run_timeout" "$run" --tag "$tag" --scene "$scene" --engine "$engine" --frames "$frames" \
    --out "$out/results.jsonl" "$@" 2>>"$out/stderr.txt" || rc=$?
  if [ $rc -ne 0 ]; then
    echo "$tag $scene $engine $* : exit $rc" | tee -a "$out/failures.txt"
  else
    printf '  %-12s %-12s %-16s %-28s %4d s\n' "$tag" "$scene" "$engine" "$*" $(( $(date +%s) - t ))
  fi
}

has_engine() { "$run" --list-engines | grep -x "$1" >/dev/null; }
engines="exact cullide cullide-1t cullide-cpu cullide-gpu cullide-gpu-exact cullide-raster cullide-sampled bullet-dbvt bullet-sap"
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
  resolutions=${BENCH_SWEEP_RESOLUTIONS:-32 64 128 256 512 1024 2048}
  for r in $resolutions; do sweep="$sweep env1:$r:3"; done
  for r in $resolutions; do sweep="$sweep env3-deform:$r:2"; done
  objects="25 50 100 250 500 1000"; tris="200 1000 2000 5000 10000 20000"; scale_frames=5
  scale_engines="cullide cullide-gpu bullet-dbvt"
  breakable_steps=300; breakable_sample=30
fi
for e in fcl-aabb fcl; do has_engine $e && scale_engines="$scale_engines $e"; done

# 1. Side by side: the exact answer first (its truth file gives the others' errors), then every engine.
for sf in $side_scenes; do
  scene=${sf%%:*}; frames=${sf##*:}
  for e in $engines; do bench side "$scene" "$e" "$frames" --truth "$out/truth/$scene.bin"; done
done
for scene in stack landscape; do
  for e in cullide $peers; do
    case $e in fcl*) continue ;; esac
    bench side $scene $e $steps
  done
done
if "$run" --list-scenes | grep -x breakable >/dev/null; then
  for e in cullide cullide-fast bullet-dbvt bullet-sap; do
    bench side breakable $e $breakable_steps --sample-every $breakable_sample
  done
else
  echo "bench: the breakable scene is not built (no cullide_demo_scene target): no breakable rows" \
    | tee -a "$out/failures.txt"
fi

# 2. Speed against error: GPU levels forced, both modes, the side-by-side truth files.
for item in $sweep; do
  IFS=: read -r scene res frames <<<"$item"
  [ -f "$out/truth/$scene.bin" ] || bench side "$scene" exact 4 --truth "$out/truth/$scene.bin"
  for e in cullide-gpu cullide-sampled; do
    bench sweep "$scene" $e "$frames" --resolution "$res" --truth "$out/truth/$scene.bin"
  done
done

# 3. Scaling: objects (env1, 200 triangles each) and triangles per object (env2, 6 tori).
# At 1,000 objects the peers get 3 frames (FCL's OBBRSS takes ~1 s a frame); CULLIDE keeps 5, so that the two GPU-levels
# frames of Auto's trial (timed, as in every run) cannot be the median (on the H100, 3 frames gave 24 ms: a trial
# frame, against 5.3 ms for the CPU path Auto chose).
for n in $objects; do
  for e in $scale_engines; do
    f=$scale_frames
    case $e in cullide*) ;; *) [ "$n" -ge 1000 ] && f=3 ;; esac
    bench scale-objects env1 $e $f --objects "$n"
  done
done
for n in $tris; do
  for e in $scale_engines; do bench scale-triangles env2 $e $scale_frames --tris "$n"; done
done
# 4. Threads: the CPU path and Auto with 1, 2, 4, ... workers up to every core (how the exact stage scales, and
# whether Auto's CPU frames keep up with the CPU path's on a machine with a GL driver's threads beside them).
cores=$(nproc)
thread_counts=""
for ((n = 1; n < cores; n *= 2)); do thread_counts="$thread_counts $n"; done
thread_counts="$thread_counts $cores"
if [ $quick -eq 1 ]; then thread_scenes="env1:3"; thread_engines="cullide-cpu"; thread_counts="1 $cores"
else thread_scenes="env1:20 env3:8"; thread_engines="cullide-cpu cullide"; fi
for sf in $thread_scenes; do
  scene=${sf%%:*}; frames=${sf##*:}
  for n in $thread_counts; do
    for e in $thread_engines; do bench threads "$scene" "$e" "$frames" --threads "$n"; done
  done
done
exit 0
