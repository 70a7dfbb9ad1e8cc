#!/usr/bin/env bash
# The test command of the README: installs what the tests need (a Vulkan driver, Xvfb for the
# viewer's window test, COLMAP for prepare's, Ray for the block driver's), then runs every test
# of the workspace (CPU reference, formats, GPU stages on lavapipe or a real GPU, the viewer in
# a virtual X window) and the Ray driver's.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-vulkan.sh
scripts/ensure-colmap.sh
# On its own line so that `set -e` stops here when the set-up fails (a failure inside the
# for-list's substitution would be ignored and the window test silently skipped).
settings=$(scripts/ensure-xvfb.sh)
for setting in $settings; do
    export "${setting?}"
done
# Fresh GPU buffers are poison-filled (NaN, 0xffffffff), so that a stage that reads memory no
# pass wrote this frame fails here instead of passing on the zeros a driver happens to give
# (TRGS_POISON_BUFFERS=0 to run without; it adds about a tenth to the tests' time).
export TRGS_POISON_BUFFERS=${TRGS_POISON_BUFFERS:-1}
# Without a desktop session Mesa's device-select layer prints libwayland's "error:
# XDG_RUNTIME_DIR is invalid or not set" at every GPU start, which reads as a failure in the
# log; the trgs commands leave the layer out themselves there (trgs_cli::headless), and so do
# the tests' own GPU starts.
if [ -z "${XDG_RUNTIME_DIR:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ] && [ -z "${MESA_VK_DEVICE_SELECT:-}" ]; then
    export NODEVICE_SELECT=1
fi
cargo test --workspace --locked "$@"
# The Ray driver (python/trgs_ray): its own tests, then a local Ray cluster training two blocks
# with the trgs binary the line above built.
profile=debug
for arg in "$@"; do
    if [ "$arg" = "--release" ]; then
        profile=release
    fi
done
python=$(scripts/ensure-ray.sh)
TRGS_BIN="$PWD/target/$profile/trgs" TRGS_RAY_REQUIRED=1 \
    "$python" -m unittest discover --start-directory python/trgs_ray/tests --verbose
