#!/usr/bin/env bash
# Makes the GPU bundle (issue #13): everything a bare x86-64 Linux machine with an NVIDIA driver (glibc >= 2.36, no
# package manager, no network) needs to run the GL tests, the benchmarks and the demo on its GPU in one command.
#   scripts/gpu-run.sh [DIR]          builds build-gpu/ (Release, stripped) and writes the bundle to DIR
#                                     (default .gpu-bundle/, git-ignored); fails if it is over 64 MiB
#   DIR/run.sh [--quick] [--device D] OUTDIR     on the GPU machine (see DIR/run.sh and docs/gpu-run.md)
# Bundle: bin/ (the programs, RUNPATH $ORIGIN/../lib), lib/ (the project's libraries and every non-glibc library
# they load, plus libglvnd's GL client libraries; RUNPATH $ORIGIN), data/meshes/ (scripts/fetch_meshes.sh's meshes
# when present), run.sh, bench-runs.sh (the benchmark run list shared with scripts/bench.sh), BUNDLE-INFO.
# Only glibc and the EGL vendor library (NVIDIA's, or Mesa's for a software rehearsal) come from the target.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
dest=${1:-.gpu-bundle}
limit=$((64 * 1024 * 1024))
t0=$(date +%s)

scripts/deps.sh >/dev/null
scripts/deps-bench >/dev/null          # FCL, the peer library the benchmark compares against
if ! command -v patchelf >/dev/null; then
  echo "gpu-run: installing patchelf"
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends patchelf >/dev/null \
    || { DEBIAN_FRONTEND=noninteractive $sudo apt-get update -qq &&
         DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends patchelf >/dev/null; }
fi
scripts/fetch_meshes.sh || true

# Release without debug info; -O2 like scripts/bench.sh's RelWithDebInfo, so the code is the CPU results' code.
# The GL tests run cullide-pairs by its build-tree path; pairs-exe.h makes that the bare name (run.sh puts the
# bundle's bin/ first on PATH).
dir=build-gpu
targets=(cullide_gl_tests cullide_bullet_tests cullide-bench-run cullide-bench-report cullide-demo cullide-pairs
  cullide-pool-bench cullide-swap-bench)
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)   # optional: speeds up rebuilds
cmake -S . -B $dir -G Ninja "${launcher[@]}" -DCMAKE_BUILD_TYPE=Release \
  "-DCMAKE_CXX_FLAGS_RELEASE=-O2 -DNDEBUG" "-DCMAKE_CXX_FLAGS=-include $root/scripts/gpu-bundle/pairs-exe.h" \
  -DCULLIDE_BUILD_CGAL_ORACLE=OFF -DCULLIDE_BUILD_TESTS=ON -DCULLIDE_BUILD_BENCHMARKS=ON >/dev/null
if ! cmake --build $dir -j"$(nproc)" --target "${targets[@]}" >$dir/build.log 2>&1; then
  grep -E -A8 'error|FAILED' $dir/build.log | head -60 >&2
  echo "gpu-run: ERROR: the build failed (whole log: $dir/build.log)" >&2
  exit 1
fi
echo "gpu-run: built in $(( $(date +%s) - t0 )) s"

rm -rf "$dest"
mkdir -p "$dest/bin" "$dest/lib" "$dest/data"
programs=(tests/cullide_gl_tests tests/bullet/cullide_bullet_tests benchmarks/cullide-bench-run
  benchmarks/cullide-bench-report demos/cullide-demo plugin/cullide-pairs benchmarks/cullide-pool-bench
  benchmarks/cullide-swap-bench)
for p in "${programs[@]}"; do
  f=$(find $dir/${p%/*} -maxdepth 1 -name "${p##*/}" -type f | head -1)
  [ -n "$f" ] || { echo "gpu-run: ERROR: $p was not built" >&2; exit 1; }
  install -m 755 "$f" "$dest/bin/"
done

# egl-diag: what the target's EGL client offers (client extensions, devices, displays, a 4.5 core context, with
# EGL_KHR_debug messages); run.sh runs it when the probe finds no hardware device.
cc -O1 -o "$dest/bin/egl-diag" scripts/gpu-bundle/egl-diag.c -ldl

# Libraries: everything the programs and the GL client libraries load, except glibc's own (the target's).
is_glibc() {
  case "$1" in
    libc.so.*|libm.so.*|libdl.so.*|libpthread.so.*|librt.so.*|ld-linux*|linux-vdso*|libresolv.so.*|libutil.so.*|\
    libanl.so.*|libmvec.so.*|libnsl.so.*|libthread_db.so.*|libBrokenLocale.so.*) return 0 ;;
  esac
  return 1
}
gl_libs=(libEGL.so.1 libOpenGL.so.0 libGL.so.1 libGLX.so.0 libGLdispatch.so.0)
libdir=/usr/lib/x86_64-linux-gnu
objects=("$dest"/bin/*)
for l in "${gl_libs[@]}"; do
  [ -e $libdir/$l ] || { echo "gpu-run: ERROR: $libdir/$l missing (Debian: libegl1 libopengl0 libgl1 libglvnd0)" >&2
                         exit 1; }
  objects+=("$libdir/$l")
done
declare -A copied=()
for o in "${objects[@]}"; do
  # ldd prints the whole closure: "name => path (addr)"; the project's own libraries resolve into build-gpu/.
  while read -r name arrow path _; do
    [ "$arrow" = "=>" ] || continue
    is_glibc "$name" && continue
    [ "$path" != "not" ] || { echo "gpu-run: ERROR: $o needs $name, which is not found" >&2; exit 1; }
    [ -n "${copied[$name]:-}" ] && continue
    cp -L "$path" "$dest/lib/$name"
    copied[$name]=$path
  done < <(ldd "$o")
done
for l in "${gl_libs[@]}"; do [ -e "$dest/lib/$l" ] || cp -L $libdir/$l "$dest/lib/$l"; done
chmod 644 "$dest"/lib/*
strip --strip-unneeded "$dest"/bin/* "$dest"/lib/*
for f in "$dest"/bin/*; do patchelf --set-rpath '$ORIGIN/../lib' "$f"; done
for f in "$dest"/lib/*; do patchelf --set-rpath '$ORIGIN' "$f"; done

if compgen -G "data/meshes/*.off" >/dev/null; then
  mkdir -p "$dest/data/meshes"
  cp data/meshes/*.off "$dest/data/meshes/"
  meshes="data/meshes: $(cd "$dest/data/meshes" && echo *.off)"
else
  meshes="no meshes (scripts/fetch_meshes.sh found none): the scenes use procedural stand-ins"
fi
install -m 755 scripts/gpu-bundle/run.sh scripts/bench-runs.sh "$dest/"

commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
git diff --quiet HEAD 2>/dev/null || commit="$commit+dirty"
{
  echo "commit: $commit"
  echo "made: $(date -u +%FT%TZ) on $(uname -m), $(ldd --version | head -1)"
  echo "build: Release (-O2 -DNDEBUG), stripped; FCL peer: $(grep -q '^CULLIDE_BENCH_FCL:BOOL=ON' $dir/CMakeCache.txt \
    && echo yes || echo no)"
  echo "bin: $(cd "$dest/bin" && echo *)"
  echo "lib: $(cd "$dest/lib" && echo *)"
  echo "$meshes"
} >"$dest/BUNDLE-INFO"

# Every program must resolve every non-glibc library inside the bundle (the loader alone, no LD_LIBRARY_PATH).
bad=0
for f in "$dest"/bin/* "$dest"/lib/*; do
  while read -r name arrow path _; do
    [ "$arrow" = "=>" ] || continue
    is_glibc "$name" && continue
    case "$(readlink -f "$path" 2>/dev/null)" in
      "$(readlink -f "$dest")"/lib/*) ;;
      *) echo "gpu-run: ERROR: ${f#"$dest"/} loads $name from $path, not from the bundle" >&2; bad=1 ;;
    esac
  done < <(env -u LD_LIBRARY_PATH ldd "$f")
done
[ $bad -eq 0 ] || exit 1

size=$(du -sb "$dest" | cut -f1)
mib=$(awk -v s="$size" 'BEGIN { printf "%.1f", s / 1048576 }')
echo "size: $mib MiB ($size bytes; limit 64 MiB)" >>"$dest/BUNDLE-INFO"
if [ "$size" -gt $limit ]; then
  echo "gpu-run: ERROR: the bundle is $mib MiB, over the 64 MiB limit" >&2
  du -sh "$dest"/* "$dest"/lib/* | sort -h | tail -12 >&2
  exit 1
fi
echo "gpu-run: $dest: $mib MiB, $(ls "$dest/bin" | wc -l) programs, $(ls "$dest/lib" | wc -l) libraries" \
  "($(( $(date +%s) - t0 )) s). On the GPU machine: $dest/run.sh OUTDIR   (or --quick)"
