#!/usr/bin/env bash
# The test command of the README: installs what the tests need, then runs every test of the
# workspace (CPU reference, formats, GPU stages on lavapipe or a real GPU).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-vulkan.sh
cargo test --workspace --locked "$@"
