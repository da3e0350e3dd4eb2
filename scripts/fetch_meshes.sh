#!/usr/bin/env bash
# Fetches the real test meshes (bunny00.off, ChineseDragon-10kv.off, armadillo.off) from Debian's libcgal-demo
# package into data/meshes/. Idempotent: does nothing when all three are present. The package is downloaded (not
# installed) into a temporary directory. The meshes have no per-file licence: they are extracted at set-up time and
# never committed (data/ is git-ignored). When the download is impossible the script prints a notice and exits 0;
# the demos and tests then use procedural stand-ins.
set -u

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="${CULLIDE_DATA_DIR:-$root/data/meshes}"
files=(bunny00.off ChineseDragon-10kv.off armadillo.off)

missing=()
for f in "${files[@]}"; do
    [[ -s "$dest/$f" ]] || missing+=("$f")
done
if [[ ${#missing[@]} -eq 0 ]]; then
    echo "fetch_meshes: all meshes present in $dest"
    exit 0
fi
echo "fetch_meshes: missing ${missing[*]}; downloading libcgal-demo"

notice() {
    echo "fetch_meshes: NOTICE: $1; demos and tests will use procedural stand-in meshes" >&2
    exit 0
}

for tool in apt-get dpkg-deb tar; do
    command -v "$tool" >/dev/null 2>&1 || notice "'$tool' is not available"
done

tmp="$(mktemp -d "${TMPDIR:-/tmp}/cullide-meshes.XXXXXX")" || notice "cannot create a temporary directory"
trap 'rm -rf "$tmp"' EXIT

if ! (cd "$tmp" && apt-get download libcgal-demo >"$tmp/apt.log" 2>&1); then
    sed 's/^/  /' "$tmp/apt.log" >&2
    notice "apt-get download libcgal-demo failed (no network or package index? try 'apt-get update')"
fi
shopt -s nullglob
debs=("$tmp"/libcgal-demo_*.deb)
shopt -u nullglob
[[ ${#debs[@]} -gt 0 ]] || notice "the downloaded package was not found"
deb="${debs[0]}"

members=()
for f in "${files[@]}"; do members+=("data/meshes/$f"); done
mkdir -p "$tmp/x"
if ! dpkg-deb --fsys-tarfile "$deb" | tar -xO ./usr/share/doc/libcgal-dev/data.tar.gz |
        tar -xz -C "$tmp/x" "${members[@]}"; then
    notice "could not extract the meshes from $(basename "$deb")"
fi

mkdir -p "$dest" || notice "cannot create $dest"
for f in "${files[@]}"; do
    if [[ -s "$tmp/x/data/meshes/$f" ]]; then
        # Write through a temporary name so an interrupted copy never leaves a truncated mesh behind.
        cp "$tmp/x/data/meshes/$f" "$dest/.$f.part" && mv -f "$dest/.$f.part" "$dest/$f"
    fi
done

still=()
for f in "${files[@]}"; do [[ -s "$dest/$f" ]] || still+=("$f"); done
if [[ ${#still[@]} -ne 0 ]]; then
    notice "still missing after extraction: ${still[*]}"
fi
echo "fetch_meshes: meshes ready in $dest"
exit 0
