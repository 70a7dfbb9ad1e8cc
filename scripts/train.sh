#!/usr/bin/env bash
# The main job of the README: installs what trgs needs, then runs `train` (on the built-in
# synthetic showcase scene when no dataset is given). Arguments are passed to `train`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-vulkan.sh
cargo run --release --locked --bin train -- "$@"
