#!/usr/bin/env bash
# The CI regression gate: build, render every scene in scenes/ at the quick tier, compare the
# run with the committed baselines (baselines/<platform-key>/quick/), and write summary.md,
# junit.xml, verdict.json and the HTML report into the run's folder. Exits with compare's
# code: 0 nothing regressed, 1 a regression, 2 an error (or the run's: 3 a scene failed). Extra
# arguments go to `aabench run`.
# With $GITHUB_STEP_SUMMARY set, the summary is appended to it.
#
# Time verdicts fail the gate only against baselines of this machine's own platform key; against
# another platform's (another CPU, Mesa or thread count) they are reported and quality alone is
# gated, since relative costs shift between CPUs (`compare --fail-on auto`).
# AABENCH_GATE_FAIL_ON=all|quality overrides.
set -uo pipefail
cd "$(dirname "$0")/.."
source ci/lib.sh
build_aabench
run_fresh gate --tier quick "$@"

"$bin" compare "$run_dir" --baseline baselines --out "$run_dir" --fail-on "${AABENCH_GATE_FAIL_ON:-auto}"
code=$?
# A scene that failed already fails compare; this keeps a run that went wrong otherwise from
# passing unnoticed.
if [ "$code" -eq 0 ] && [ "$run_code" -ne 0 ]; then code=$run_code; fi
"$bin" report "$run_dir" >/dev/null || echo "ci/gate.sh: the HTML report could not be written" >&2
if [ -n "${GITHUB_STEP_SUMMARY:-}" ] && [ -f "$run_dir/summary.md" ]; then
    cat "$run_dir/summary.md" >>"$GITHUB_STEP_SUMMARY"
fi
echo "ci/gate.sh: $run_dir/summary.md, junit.xml, verdict.json, index.html (exit $code)" >&2
exit "$code"
