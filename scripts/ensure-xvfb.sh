#!/usr/bin/env bash
# The viewer's window test runs the viewer under Xvfb (a virtual X server). As root on
# Debian/Ubuntu this installs Xvfb when it is missing, and then prints TRGS_REQUIRE_XVFB=1 so the
# caller makes the test fail rather than skip if Xvfb still cannot run it. Elsewhere it says what
# to install; the test then reports that it was skipped.
set -euo pipefail

if command -v Xvfb >/dev/null 2>&1; then
    echo "TRGS_REQUIRE_XVFB=1"
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    echo "trgs: no Xvfb found; installing it for the viewer's window test (xvfb)" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq --no-install-recommends xvfb >/dev/null
    echo "TRGS_REQUIRE_XVFB=1"
    exit 0
fi
echo "trgs: no Xvfb found (sudo apt-get install xvfb); the viewer's window test will be skipped" >&2
