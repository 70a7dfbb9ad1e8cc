#!/usr/bin/env bash
# Make sure a Vulkan driver is installed. trgs renders with wgpu on any Vulkan adapter; machines
# without a GPU use Mesa's lavapipe (a CPU Vulkan driver). As root, this installs it when no
# Vulkan driver manifest (ICD) is present; otherwise it says what to install.
set -euo pipefail

have_icd() {
    local d
    for d in /usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d; do
        if compgen -G "$d/*.json" >/dev/null; then
            return 0
        fi
    done
    [ -n "${VK_ICD_FILENAMES:-}${VK_DRIVER_FILES:-}" ]
}

if have_icd; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    echo "trgs: no Vulkan driver found; installing Mesa's lavapipe (mesa-vulkan-drivers)" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq mesa-vulkan-drivers >/dev/null
    have_icd && exit 0
    echo "trgs: mesa-vulkan-drivers installed but no Vulkan driver manifest was found" >&2
    exit 1
fi
cat >&2 <<'MSG'
trgs: no Vulkan driver found. Install one, e.g. Mesa's CPU driver lavapipe:
    sudo apt-get install mesa-vulkan-drivers        (Debian/Ubuntu)
    sudo dnf install mesa-vulkan-drivers            (Fedora)
or your GPU vendor's Vulkan driver. Tests that need no GPU still run.
MSG
exit 0
