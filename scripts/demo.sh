#!/usr/bin/env bash
# Installs what is missing, builds, and runs the breakable-object demo headless into out/demo/ (frames.csv,
# summary.json, snapshots/*.png, contact_sheet.png). Extra arguments go to cullide-demo, e.g.
#   scripts/demo.sh --scene env2 --frames 20 --out out/env2
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/fetch_meshes.sh || true  # without the real meshes the demo uses procedural stand-ins (with a notice)
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target cullide-demo
export MESA_SHADER_CACHE_DIR="$PWD/build/mesa-shader-cache"
build/demos/cullide-demo "$@"
