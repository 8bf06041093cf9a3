#!/usr/bin/env bash
# The default suite: set up the machine if needed, then render every scene in scenes/ in every
# mode of the tier (quick unless `--tier nightly` is given) and write reports/<run-id>/.
# Extra arguments go to `aabench run`, e.g. `ci/suite.sh --tier nightly`.
set -euo pipefail
cd "$(dirname "$0")/.."
ci/setup.sh
cargo build --release --locked -p aabench
exec target/release/aabench run "$@"
