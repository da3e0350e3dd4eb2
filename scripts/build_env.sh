# Sourced (from the repository root) by scripts/test.sh and scripts/fuzz.sh: how their build trees are configured.
#
# Compiler cache: ccache (scripts/deps.sh installs it) in its own directory, outside the clone ($CCACHE_DIR, else
# ccache's default, ~/.cache/ccache). base_dir is the clone and hash_dir is off, so a compile already done in another
# clone or another build tree of the same commit is a hit: a fresh clone in CI reuses a developer's scripts/test.sh
# build, and the double-precision Bullet tree (build-f64/) reuses the core libraries compiled for build/. An object
# taken from the cache keeps the compile directory of the tree that first made it in its debug info. A CCACHE_BASEDIR
# or CCACHE_HASHDIR already in the environment wins.
#
# Generator: Ninja for a new build tree; a tree configured before keeps the generator it has (CMake refuses to
# change it).
#
# Sets the array cullide_cmake_args (compiler launcher); cullide_generator_args DIR prints the generator option for DIR.
cullide_cmake_args=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
  [ -n "${CCACHE_HASHDIR:-}" ] || export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-true}"
  cullide_cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cullide_generator_args() {
  if [ ! -f "$1/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then
    echo "-G Ninja"
  fi
}
