#!/usr/bin/env bash
# Installs what is missing, fetches the real test data (scripts/fetch-data: checksummed,
# cached, ~1 min cold, instant warm), then runs the whole check: formatting, clippy with
# warnings as errors, and the test suite on lavapipe (or the GPU REFRAKT_DEVICE names)
# with the validation layer and synchronization validation on. Any validation message
# fails a test; with REFRAKT_REQUIRE_DATA=1 a missing real file fails its test too.
# The viewer's test opens a real window under Xvfb (started by the test when DISPLAY is
# unset).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/setup-data.sh
source scripts/env.sh
scripts/fetch-data
export REFRAKT_REQUIRE_DATA=1
# setup.sh installed Xvfb, so the viewer's window test must run, not skip.
export REFRAKT_REQUIRE_DISPLAY="${REFRAKT_REQUIRE_DISPLAY:-1}"
cargo fmt --all -- --check
cargo clippy --all-targets --locked -- -D warnings
cargo test --locked "$@"
