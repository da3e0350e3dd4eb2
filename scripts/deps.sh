#!/usr/bin/env bash
# Installs the Debian 12 packages the project needs (only those missing). Runs apt-get as root, or via sudo.
# ninja-build and ccache are for the build scripts (scripts/build_env.sh: the generator and the compiler cache kept
# outside the clone); clang and libclang-rt-14-dev for scripts/fuzz.sh (libFuzzer); libcgal-dev for the oracle test;
# glslang-tools for the shader validation test.
set -euo pipefail
packages=(cmake g++ make ninja-build ccache pkg-config git
  libbullet-dev libbullet-extras-dev libeigen3-dev libepoxy-dev libegl-dev libegl1 libegl-mesa0 libgl1-mesa-dri
  libgtest-dev libgmock-dev nlohmann-json3-dev libcgal-dev libpng-dev clang libclang-rt-14-dev ccache glslang-tools)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "deps: installing ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
