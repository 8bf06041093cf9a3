#!/usr/bin/env bash
# The test command: set up the machine if needed (lavapipe, and Chromium for the report's
# browser test), then build in release (the profile results are filed under) and run every
# test on lavapipe.
set -euo pipefail
cd "$(dirname "$0")/.."
ci/setup.sh --browser
# Mesa's device-select layer prints a harmless XDG_RUNTIME_DIR line per device; quiet it.
export NODEVICE_SELECT=1
cargo test --release --workspace --locked "$@"
