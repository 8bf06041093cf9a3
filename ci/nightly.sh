#!/usr/bin/env bash
# The nightly report: every scene at 1024×768 (the paper's resolution), ablations included.
set -euo pipefail
exec "$(dirname "$0")/suite.sh" --tier nightly "$@"
