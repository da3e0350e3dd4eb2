#!/usr/bin/env bash
# The GPU bundle's one command (made by scripts/gpu-run.sh; docs/gpu-run.md):
#   run.sh [--quick] [--device hardware|software|surfaceless|N] OUTDIR
# 1. prints the machine, the driver and the EGL device/renderer CULLIDE picks (cullide-bench-run --probe);
# 2. runs the GL tests (CI=true: a missing device fails) -> OUTDIR/gl-tests.json, the Bullet adapter tests ->
#    OUTDIR/bullet-tests-N.json (in shards, beside the GL tests), a short headless demo -> OUTDIR/demo/, the pool's
#    fork/join cost -> OUTDIR/pool-bench.txt, and the two-line swap's benchmark -> OUTDIR/swap.{txt,json};
# 3. runs the benchmarks: bench-runs.sh, the same run list as scripts/bench.sh (--quick: its quick list);
# 4. cullide-bench-report: OUTDIR/results-gpu.json (results + machine, device, renderer, driver), OUTDIR/benchmarks.md,
#    OUTDIR/plotdata/ (gnuplot scripts; PNGs in OUTDIR/plots/ only where gnuplot is installed);
# 5. OUTDIR/log.txt holds everything printed. A failing step is logged and the next one still runs; the exit status
#    is 0 only when every step passed.
# The device is CULLIDE_GL_DEVICE (default hardware; --device overrides). EGL vendor: an existing
# __EGL_VENDOR_LIBRARY_FILENAMES, else /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json if present (hardware
# device only), else libglvnd's defaults. Time: everything ends within GPU_RUN_BUDGET_S (default 500 s; benchmark runs
# that would start later are skipped and listed as failures), each benchmark run within BENCH_RUN_TIMEOUT (90 s).
set -uo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage() { echo "usage: run.sh [--quick] [--device hardware|software|surfaceless|N] OUTDIR" >&2; exit 2; }
quick=0 device="" outdir=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --device) [ $# -ge 2 ] || usage; device=$2; shift ;;
    --device=*) device=${1#--device=} ;;
    -h|--help) usage ;;
    -*) usage ;;
    *) [ -z "$outdir" ] || usage; outdir=$1 ;;
  esac
  shift
done
[ -n "$outdir" ] || usage
mkdir -p "$outdir" || exit 2
out=$(cd "$outdir" && pwd)
rm -rf "$out/bench" "$out/demo" "$out/plots" "$out/plotdata" "$out/cache" "$out/tmp" "$out/results-gpu.json" \
  "$out/gl-tests.json" "$out"/bullet-tests-*.json "$out/benchmarks.md" "$out/log.txt" "$out/swap.txt" \
  "$out/swap.json" "$out/swap-lost.txt" "$out/pool-bench.txt"
exec > >(tee "$out/log.txt") 2>&1
tee_pid=$!
t0=$(date +%s)
budget=${GPU_RUN_BUDGET_S:-500}
mode=$([ $quick -eq 1 ] && echo quick || echo full)

export PATH="$here/bin:$PATH"           # the GL tests run cullide-pairs by its bare name
export CULLIDE_DATA_DIR="$here/data/meshes"
export CULLIDE_GL_DEVICE=${device:-${CULLIDE_GL_DEVICE:-hardware}}
export CI=true
nvidia_json=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ] && [ -f $nvidia_json ] && [ "$CULLIDE_GL_DEVICE" != software ] &&
   [ "$CULLIDE_GL_DEVICE" != surfaceless ]; then
  export __EGL_VENDOR_LIBRARY_FILENAMES=$nvidia_json
fi
mkdir -p "$out/cache"
export __GL_SHADER_DISK_CACHE_PATH="$out/cache" MESA_SHADER_CACHE_DIR="$out/cache"

failed=()
steps_json=""
# step NAME TIMEOUT COMMAND...: runs it (logged), records its status; never stops the script.
step() {
  local name=$1 limit=$2
  shift 2
  local t=$(date +%s) rc=0
  echo
  echo "=== $name ($(( t - t0 )) s in)"
  timeout "$limit" "$@" || rc=$?
  record "$name" $rc $(( $(date +%s) - t )) "$limit"
}
# record NAME EXIT SECONDS LIMIT: a step's outcome, in the log, the failed list and steps.json.
record() {
  local name=$1 rc=$2 took=$3 limit=$4
  if [ "$rc" -eq 0 ]; then echo "=== $name: ok ($took s)"
  else
    [ "$rc" -eq 124 ] && echo "=== $name: timed out after $limit s" || echo "=== $name: FAILED, exit $rc ($took s)"
    failed+=("$name")
  fi
  steps_json="$steps_json${steps_json:+, }\"$name\": {\"exit\": $rc, \"seconds\": $took}"
}
esc() { printf '%s' "$1" | sed 's/\\/\\\\/g; s/"/\\"/g'; }

echo "run.sh $mode: bundle $here, out $out"
cat "$here/BUNDLE-INFO" 2>/dev/null | sed 's/^/  /'
echo "machine: $(uname -srm), $(nproc) cores, glibc $(getconf GNU_LIBC_VERSION 2>/dev/null | cut -d' ' -f2)"
echo "CULLIDE_GL_DEVICE=$CULLIDE_GL_DEVICE __EGL_VENDOR_LIBRARY_FILENAMES=${__EGL_VENDOR_LIBRARY_FILENAMES:-(libglvnd defaults)}"

# 1. Device, driver, renderer; and where each library comes from (only glibc and the EGL vendor's from the system).
driver="" gpu="" driver_version=""
if command -v nvidia-smi >/dev/null 2>&1; then
  nvidia-smi -L || true
  driver=$(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -1)
  gpu=${driver%,*}; driver_version=${driver##*, }
  echo "driver: $driver"
else
  echo "driver: no nvidia-smi"
fi
probe_file="$out/cache/probe.json"
mkdir -p "$out/cache/ld-debug"
step probe 120 bash -c 'LD_DEBUG=libs LD_DEBUG_OUTPUT="$3" "$1" --probe >"$2"; rc=$?; cat "$2"; exit $rc' _ \
  "$here/bin/cullide-bench-run" "$probe_file" "$out/cache/ld-debug/probe"
# What the probe loaded (dlopen'ed GL libraries and the EGL vendor's included), by where it came from.
loaded=$(cat "$out"/cache/ld-debug/probe.* 2>/dev/null | sed -n 's/.*calling init: //p' | sort -u)
echo "probe loaded from the bundle: $(printf '%s\n' "$loaded" | grep "^$here/" | sed 's,.*/,,' | tr '\n' ' ')"
echo "probe loaded from the system (glibc, the EGL vendor and its own libraries): $(printf '%s\n' "$loaded" |
  grep -v "^$here/" | sed 's,.*/,,' | tr '\n' ' ')"
probe=$(cat "$probe_file" 2>/dev/null)
[ -n "$probe" ] || probe='{"renderer":"","device":"none"}'
case "$probe" in
  *llvmpipe*|*softpipe*|*'"renderer":""'*) class=cpu ;;
  *) class=gpu ;;
esac
renderer=$(printf '%s' "$probe" | sed -n 's/.*"renderer": *"\([^"]*\)".*/\1/p')
egl_device=$(printf '%s' "$probe" | sed -n 's/.*"device": *"\([^"]*\)".*/\1/p')

if [ $class = cpu ] && [ -x "$here/bin/egl-diag" ]; then
  echo "no hardware device: what the EGL client offers (egl-diag):"
  timeout 60 "$here/bin/egl-diag" 2>&1 | cut -c1-400 | sed 's/^/  /'
fi
# On a hardware device the resolution sweep goes on to 4096² (issue #15); on llvmpipe it stops at 2048².
[ $class = gpu ] && export BENCH_SWEEP_RESOLUTIONS=${BENCH_SWEEP_RESOLUTIONS:-32 64 128 256 512 1024 2048 4096}

# 2. Tests on the device, and the demo.
mkdir -p "$out/tmp"
export TMPDIR="$out/tmp"
if [ $quick -eq 1 ]; then tests_limit=150; demo_frames=30; else tests_limit=240; demo_frames=120; fi
# The GL tests and the Bullet adapter tests run side by side, the adapter's in shards (its tests are CPU-bound and
# independent; each shard is its own process with its own culler and GL context): device time is scarce.
shards=$(( $(nproc) / 4 )); [ $shards -ge 1 ] || shards=1; [ $shards -le 4 ] || shards=4
bullet_shards() {
  local i pids=() rc=0
  for ((i = 0; i < shards; i++)); do
    GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i "$here/bin/cullide_bullet_tests" \
      --gtest_output=json:"$out/bullet-tests-$i.json" >"$out/tmp/bullet-tests-$i.txt" 2>&1 &
    pids+=($!)
  done
  for ((i = 0; i < shards; i++)); do wait ${pids[$i]} || rc=$?; done
  for ((i = 0; i < shards; i++)); do
    echo "--- shard $i of $shards:"; grep -E '^\[  (PASSED|FAILED) |^\[==========\]|tests? (FAILED|failed)' \
      "$out/tmp/bullet-tests-$i.txt" || tail -20 "$out/tmp/bullet-tests-$i.txt"
  done
  return $rc
}
export -f bullet_shards
export here out shards
t_bullet=$(date +%s)
echo "=== bullet-tests ($(( t_bullet - t0 )) s in): $shards shards beside the GL tests"
# The background run writes "EXIT SECONDS" (its own time, not the GL tests') for record.
( rc=0; timeout $tests_limit bash -c bullet_shards >"$out/tmp/bullet-tests.txt" 2>&1 || rc=$?
  echo "$rc $(( $(date +%s) - t_bullet ))" >"$out/tmp/bullet-tests.rc" ) &
bullet_pid=$!
step gl-tests $tests_limit "$here/bin/cullide_gl_tests" --gtest_output=json:"$out/gl-tests.json"
wait $bullet_pid
echo
cat "$out/tmp/bullet-tests.txt"
read -r bullet_rc bullet_s <"$out/tmp/bullet-tests.rc" 2>/dev/null
[[ "${bullet_rc:-}" =~ ^[0-9]+$ ]] || bullet_rc=1     # no status written: the background run died
[[ "${bullet_s:-}" =~ ^[0-9]+$ ]] || bullet_s=$(( $(date +%s) - t_bullet ))
record bullet-tests $bullet_rc $bullet_s $tests_limit
step demo 120 "$here/bin/cullide-demo" --frames $demo_frames --check-every 15 --snapshot-every $demo_frames --quiet \
  --out "$out/demo"
# The worker pool's fork/join cost by thread count (the CPU stages make a few dozen parallelFor calls a frame).
step pool-bench 60 bash -c 'set -o pipefail; "$1" --calls 500 | tee "$2"' _ "$here/bin/cullide-pool-bench" \
  "$out/pool-bench.txt"
# The two-line swap (CullideBroadphase + CullideCollisionDispatcher, GpuLevels::Auto) against Bullet's default
# pipeline and btAxisSweep3 on typical scenes, in lockstep in one process: OUTDIR/swap.txt and swap.json.
# Its stderr (the first lost pairs explained, or why it failed) goes to swap-lost.txt; the end of it to the log.
# Limit: 2 s a step, at least 120 s (60 steps took 14-32 s on the H100 machine; tori-pile slows down past 60).
if [ $quick -eq 1 ]; then swap_steps=10; else swap_steps=${SWAP_STEPS:-60}; fi
swap_limit=$(( 2 * swap_steps > 120 ? 2 * swap_steps : 120 ))
step swap-bench $swap_limit bash -c 'set -o pipefail; "$1" --steps "$2" --json "$3/swap.json" 2>"$3/swap-lost.txt" |
  tee "$3/swap.txt"' _ "$here/bin/cullide-swap-bench" $swap_steps "$out"
[ -s "$out/swap-lost.txt" ] && { echo "swap-bench: stderr (last 5 lines):"; tail -5 "$out/swap-lost.txt"; }

# 3. The benchmarks: the run list of scripts/bench.sh.
t_bench=$(date +%s)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
left=$(( t0 + budget - t_bench - 20 ))
[ $left -gt 30 ] || left=30
export BENCH_RUN_TIMEOUT=${BENCH_RUN_TIMEOUT:-90} BENCH_DEADLINE=$(( t_bench + left - ${BENCH_RUN_TIMEOUT:-90} ))
[ $BENCH_DEADLINE -gt $t_bench ] || BENCH_DEADLINE=$(( t_bench + 10 ))
echo "benchmark runs start until $(( BENCH_DEADLINE - t0 )) s in, each within $BENCH_RUN_TIMEOUT s"
step bench $(( left + 30 )) bash "$here/bench-runs.sh" "$here/bin/cullide-bench-run" "$out/bench" \
  $([ $quick -eq 1 ] && echo --quick)
if [ -s "$out/bench/failures.txt" ]; then
  echo "bench: failing or skipped runs:"; sed 's/^/  /' "$out/bench/failures.txt"
  case " ${failed[*]} " in *" bench "*) ;; *) failed+=(bench-runs) ;; esac
fi
[ -s "$out/bench/stderr.txt" ] && { echo "bench: stderr (last 10 lines):"; tail -10 "$out/bench/stderr.txt"; }

# 4. results-gpu.json (results + machine) and the report.
mem_kb=0
while read -r k v _; do [ "$k" = MemTotal: ] && mem_kb=$v; done </proc/meminfo
steps_json="$steps_json${steps_json:+, }\"bench-runs\": {\"failed_runs\": $(cat "$out/bench/failures.txt" 2>/dev/null |
  wc -l)}"
cat >"$out/bench/machine.json" <<JSON
{"class": "$class", "quick": $([ $quick -eq 1 ] && echo true || echo false), "bundle": true,
 "date": "$(date -u +%FT%TZ)", "cpu": "$(esc "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')")",
 "cores": $(nproc), "memory_gib": $(( mem_kb / 1048576 )).$(( mem_kb * 10 / 1048576 % 10 )),
 "kernel": "$(uname -r)", "mesa_package": "", "nvidia": "$(esc "$driver")",
 "gpu": "$(esc "$gpu")", "driver_version": "$(esc "$driver_version")",
 "device": "$(esc "$egl_device")", "renderer": "$(esc "$renderer")", "gl_device_setting": "$(esc "$CULLIDE_GL_DEVICE")",
 "probe": $probe, "load_before": "$load_before", "load_after": "$(cut -d' ' -f1-3 /proc/loadavg)",
 "commit": "$(esc "$(sed -n 's/^commit: //p' "$here/BUNDLE-INFO" 2>/dev/null)")",
 "runtime_s": $(( $(date +%s) - t_bench )), "build_s": 0, "steps": {$steps_json}}
JSON
report() {
  "$here/bin/cullide-bench-report" combine --records "$out/bench/results.jsonl" --machine "$out/bench/machine.json" \
    --out "$out/results-gpu.json" || return 1
  mkdir -p "$out/plots" "$out/plotdata"
  "$here/bin/cullide-bench-report" render --docs "$out/benchmarks.md" --plots "$out/plots" --data "$out/plotdata" \
    "$out/results-gpu.json" || return 1
  if command -v gnuplot >/dev/null 2>&1; then
    # A plot without data (runs skipped) is a warning: the results and the report are what count.
    for gp in "$out"/plotdata/*.gp; do gnuplot "$gp" || echo "warning: gnuplot $gp failed"; done
  else
    echo "no gnuplot here: the plots' data and scripts are in plotdata/ (run gnuplot on them elsewhere)"
  fi
}
export -f report
export here out
step report 60 bash -c report

# 5. Summary.
echo
echo "run.sh $mode: done in $(( $(date +%s) - t0 )) s; device: ${egl_device:-none}; renderer: ${renderer:-none}"
echo "  $out/results-gpu.json, $out/gl-tests.json, $out/benchmarks.md, $out/log.txt"
status=0
if [ ${#failed[@]} -gt 0 ]; then echo "FAILED: ${failed[*]}"; status=1; else echo "all steps passed"; fi
exec >&- 2>&-
wait $tee_pid
exit $status
