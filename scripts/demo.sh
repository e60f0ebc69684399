#!/usr/bin/env bash
# Installs what is missing, builds refrakt (release) and renders the default scene,
# printing where the image went and the GPU time of each pass. Extra arguments go to
# `refrakt render`, e.g. scripts/demo.sh -o shell.exr --width 768 --height 768
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source scripts/env.sh
cargo build --release --locked
./target/release/refrakt info | sed -n '1,4p'
exec ./target/release/refrakt render "$@"
