#!/usr/bin/env bash
# The far-outlier hard case of docs/reliability.md (issue #13): two overlapping unit cubes at the origin and a third
# at (s, s, s), through the installed-style CLI, for every pipeline and resolution. Prints a markdown table of the
# answer (triangle pairs; the exact answer is 18), the wall time and the peak memory of each run.
# Usage: scripts/far-outliers.sh [BUILD_DIR] (default: build). GPU levels are forced (--gpu-levels always).
set -euo pipefail
build=${1:-build}
pairs="$build/plugin/cullide-pairs"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/cube.off" <<'MESH'
OFF
8 12 0
0 0 0
1 0 0
0 1 0
1 1 0
0 0 1
1 0 1
0 1 1
1 1 1
3 0 2 3
3 0 3 1
3 4 5 7
3 4 7 6
3 0 1 5
3 0 5 4
3 2 6 7
3 2 7 3
3 0 4 6
3 0 6 2
3 1 3 7
3 1 7 5
MESH
scene() {  # scene FILE [S]: the two cubes, and the outlier at (S, S, S) when S is given
    local at=""
    if [[ $# -gt 1 ]]; then at=", {\"mesh\": \"cube.off\", \"transform\": [1,0,0,$2, 0,1,0,$2, 0,0,1,$2, 0,0,0,1]}"; fi
    echo "{\"objects\": [{\"mesh\": \"cube.off\"}, {\"mesh\": \"cube.off\", \"transform\": [1,0,0,0.5, 0,1,0,0.5, 0,0,1,0.5, 0,0,0,1]}$at]}" > "$1"
}
scene "$work/none.json"
for s in 1e8 1e13 1e20 1e38 1e39 1e300; do scene "$work/$s.json" "$s"; done
echo "| outlier at | pipeline | 16² | 256² | 1024² | 4096² |"
echo "|---|---|---|---|---|---|"
for s in none 1e8 1e13 1e20 1e38 1e39 1e300; do
    for pipeline in auto paper; do
        row="| $s | $pipeline |"
        for r in 16 256 1024 4096; do
            /usr/bin/time -f "%e %M" -o "$work/time" "$pairs" "$work/$s.json" --pipeline "$pipeline" --resolution "$r" \
                --gpu-levels always --out "$work/out.json" 2> "$work/err" || { row="$row exit $? |"; continue; }
            n=$(python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['triangle_pairs']))" "$work/out.json")
            read -r seconds kb < "$work/time"
            row="$row $n pairs, ${seconds} s, $((kb / 1024)) MB |"
        done
        echo "$row"
    done
done
