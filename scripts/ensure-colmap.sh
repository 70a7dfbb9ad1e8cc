#!/usr/bin/env bash
# Make sure COLMAP's `colmap` program is installed: `prepare` runs it, and its test prepares the
# built-in scene's photos. As root with apt-get, this installs Debian's package when `colmap` is
# missing; otherwise it says what to install.
set -euo pipefail

if command -v colmap >/dev/null 2>&1; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    echo "trgs: COLMAP not found; installing Debian's colmap package" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq colmap >/dev/null
    command -v colmap >/dev/null 2>&1 && exit 0
    echo "trgs: the colmap package installed no colmap program" >&2
    exit 1
fi
cat >&2 <<'MSG'
trgs: COLMAP not found (prepare needs the colmap program). Install it:
    sudo apt-get install colmap        (Debian/Ubuntu)
    brew install colmap                (macOS)
The prepare test fails without it.
MSG
exit 0
