#!/usr/bin/env bash
# Installs what is missing, builds, and runs the demo headless into out/.
# Until the breakable-object demo (issue #4) lands, the demo is cullide-pairs on a generated example scene.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/fetch_meshes.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target cullide-pairs cullide-example-scene
mkdir -p out/demo
scene=$(build/scenes/cullide-example-scene out/demo/scene)
build/plugin/cullide-pairs "$scene" --out out/demo/pairs.json "$@"
python3 - out/demo/pairs.json <<'PY' 2>/dev/null || echo "demo: wrote out/demo/pairs.json"
import json, sys
r = json.load(open(sys.argv[1]))
s = r["stats"]
print(f"demo: {r['objects']} objects, {s['triangles']} triangles -> {len(r['object_pairs'])} colliding object pairs, "
      f"{len(r['triangle_pairs'])} intersecting triangle pairs in {s['total_ms']:.1f} ms on {s['renderer']}")
print("demo: wrote out/demo/pairs.json")
PY
