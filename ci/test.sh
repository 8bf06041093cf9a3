#!/usr/bin/env bash
# The test command: set up the machine if needed (lavapipe, Chromium for the report's browser
# test, and actionlint for the workflows), then build in release (the profile results are filed under) and run every
# test on lavapipe. Tests that need root, Chromium or Node.js are listed as ignored, with the reason;
# `ci/test.sh -- --include-ignored` runs them too (`.ci/run` does).
set -euo pipefail
cd "$(dirname "$0")/.."
ci/setup.sh --browser --lint
# Mesa's device-select layer prints a harmless XDG_RUNTIME_DIR line per device; quiet it.
export NODEVICE_SELECT=1
cargo test --release --workspace --locked "$@"
