#!/usr/bin/env bash
# Installs what aabench needs on a fresh Debian/Ubuntu machine: lavapipe (Mesa's CPU Vulkan
# driver) when no lavapipe driver manifest is present. Rust comes from rustup, as on the CI
# machines. Safe to run again: it installs only what is missing.
set -euo pipefail

have_lavapipe() {
    compgen -G "/usr/share/vulkan/icd.d/lvp_icd*.json" >/dev/null ||
        compgen -G "/etc/vulkan/icd.d/lvp_icd*.json" >/dev/null
}

if ! have_lavapipe; then
    echo "ci/setup.sh: installing lavapipe (mesa-vulkan-drivers)" >&2
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    # A fresh machine may have empty package lists: update only when the install needs it.
    $sudo apt-get install -y --no-install-recommends mesa-vulkan-drivers >/dev/null 2>&1 || {
        $sudo apt-get update -qq
        $sudo apt-get install -y --no-install-recommends mesa-vulkan-drivers
    }
    have_lavapipe || { echo "ci/setup.sh: lavapipe is still missing after the install" >&2; exit 1; }
fi

if ! command -v cargo >/dev/null 2>&1; then
    echo "ci/setup.sh: cargo is missing; install Rust with https://rustup.rs" >&2
    exit 1
fi
