#!/usr/bin/env bash
# The nightly report: every scene at 1024×768 (the paper's resolution), ablations included;
# compared with the nightly baselines when there are any; the run's record appended to the
# history folder ($AABENCH_HISTORY, default reports/history); and the HTML report written with
# the history plotted. Exits with compare's code (0 when there are no nightly baselines yet).
# Extra arguments go to `aabench run`.
set -uo pipefail
cd "$(dirname "$0")/.."
source ci/lib.sh
build_aabench
history="${AABENCH_HISTORY:-reports/history}"
run_fresh nightly --tier nightly "$@"

mkdir -p "$history"
cp "$run_dir/run.json" "$history/$(basename "$run_dir").json"
# A report, not the gate: before the first nightly bless there is nothing to compare with.
lenient=()
if ! compgen -G "baselines/*/nightly" >/dev/null; then lenient=(--lenient); fi
"$bin" compare "$run_dir" --baseline baselines --out "$run_dir" "${lenient[@]}"
code=$?
"$bin" report "$run_dir" --history "$history" || code=2
echo "ci/nightly.sh: $run_dir/index.html (exit $code)" >&2
exit "$code"
