#!/usr/bin/env bash
# Render the three image-quality comparison scenes with a given refrakt binary.
#   usage: render.sh BINARY OUTDIR
# Writes OUTDIR/sphere-on-floor.png, OUTDIR/glass.png, OUTDIR/lung-ct.png (256x256),
# each with --softness 0 --specular 0 (hard light, no highlights) so that banding and
# noise are not hidden. Prints each command line and refrakt's own timing output, plus
# the wall time of each render. Scene data must already be in ~/.cache/refrakt (or
# $REFRAKT_CACHE_DIR / $REFRAKT_DATA_DIR).
set -euo pipefail

if [ $# -ne 2 ]; then
  echo "usage: $0 BINARY OUTDIR" >&2
  exit 2
fi
BIN=$1
OUT=$2
mkdir -p "$OUT"

SIZE=(--width 256 --height 256)
COMMON=(--softness 0 --specular 0)

run() {
  local name=$1
  shift
  local cmd=("$BIN" render "$@" "${SIZE[@]}" "${COMMON[@]}" -o "$OUT/$name.png")
  echo "+ ${cmd[*]}"
  local t0 t1
  t0=$(date +%s.%N)
  "${cmd[@]}" 2>&1
  t1=$(date +%s.%N)
  printf '  %s: wall %.1f s\n\n' "$name" "$(echo "$t1 - $t0" | bc -l)"
}

# Glass sphere over its floor, oblique camera; the default light comes from above,
# tilted towards the camera. Target lowered so the lit floor around the sphere fills
# the lower part of the frame.
run sphere-on-floor sphere-on-floor --azimuth 30 --elevation 30 --distance 1.9 --target 0,-0.1,0

# Wine glass stand-in (thesis Fig. 6.3) at a quarter of its resolution.
run glass glass --scale 0.25

# Real chest CT, scene defaults.
run lung-ct lung-ct
