#!/usr/bin/env bash
# Renders every built-in scene worth showing (the demo, the eight thesis stand-ins at 0.4 of
# their resolution, the real CT and MRI scans) at 256x256 and lays them out in
# docs/scenes.png, in this order, four to a row. Needs scripts/fetch-data for the real scans.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
cargo build --release --locked --examples --bins
out=$(mktemp -d)
scenes=(sphere-on-floor supernova piggy-bank glass hand head water ship kiwi lung-ct mri-head)
files=()
for s in "${scenes[@]}"; do
  extra=()
  case $s in
    sphere-on-floor|lung-ct|mri-head) ;;
    *) extra=(--scale 0.4) ;;
  esac
  echo "rendering $s" >&2
  ./target/release/refrakt render "$s" "${extra[@]}" --width 256 --height 256 -o "$out/$s.png" >/dev/null
  files+=("$out/$s.png")
done
# The wine glass again, in front of a shipped CC0 map (assets/env).
./target/release/refrakt render glass --scale 0.4 --width 256 --height 256 \
  --env assets/env/city.exr -o "$out/glass-city.png" >/dev/null
files+=("$out/glass-city.png")
./target/release/examples/contact_sheet docs/scenes.png "${files[@]}"
echo "wrote docs/scenes.png" >&2
