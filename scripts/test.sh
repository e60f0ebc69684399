#!/usr/bin/env bash
# Installs what is missing, then runs the whole check: formatting, clippy with warnings as
# errors, and the test suite on lavapipe (or the GPU REFRAKT_DEVICE names) with the
# validation layer and synchronization validation on. Any validation message fails a test.
# The viewer's test opens a real window under Xvfb (started by the test when DISPLAY is
# unset).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source scripts/env.sh
# setup.sh installed Xvfb, so the viewer's window test must run, not skip.
export REFRAKT_REQUIRE_DISPLAY="${REFRAKT_REQUIRE_DISPLAY:-1}"
cargo fmt --all -- --check
cargo clippy --all-targets --locked -- -D warnings
cargo test --locked "$@"
