#!/usr/bin/env bash
# Make sure the Ray driver (python/trgs_ray) and Ray are installed for its tests: a virtual
# environment in target/ray-venv (beside the build, so a clean clone makes its own), with the
# package installed from this checkout. Prints the environment's python.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/ray-venv
python=${PYTHON:-python3}
if ! command -v "$python" >/dev/null 2>&1; then
    echo "trgs: $python not found; the Ray driver's tests need Python 3.9 or newer with venv and pip" >&2
    exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
    mkdir -p target
    "$python" -m venv "$venv" >&2
fi
# Quiet unless it fails; the package is installed anew each time so that its tests run this
# checkout's code through its own pyproject.
if ! log=$("$venv/bin/python" -m pip install --disable-pip-version-check -q ./python/trgs_ray 2>&1); then
    echo "$log" >&2
    echo "trgs: installing python/trgs_ray and Ray into $venv failed" >&2
    exit 1
fi
echo "$venv/bin/python"
