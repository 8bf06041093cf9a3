#!/usr/bin/env bash
# The CI regression gate. Quality, output hashes, sample statistics and the presence of every
# scene and mode are gated against the committed baselines (baselines/<platform-key>/quick/).
# Time is gated against the *base build measured on this machine in this job*: in-run time
# ratios shift 15–40 % between CPU generations, so numbers blessed on another machine cannot
# decide time here.
#
#   ci/gate.sh [--base REF] [--shard I/N] [--verdict-out DIR] [--alongside CMD] [aabench run arguments…]
#
# With --alongside CMD the gate runs the shell command CMD (`.ci/run`: the tests) beside the
# head's quality process, which gives no time, and ends it before the base's build and any
# process it times: on 2 cores the quality process and the tests took 420 s side by side against
# about 630 s one after the other. CMD failing fails the gate (exit 4) after its verdict.
#
# With --shard I/N the gate renders scenes I, I+N, … of the suite in every process (not in the
# fresh processes that confirm a regression: they render the scenes named), and compares them
# with the baselines of those scenes: one job of a CI matrix, whose verdicts
# `aabench merge-verdicts` joins. --verdict-out copies summary.md, junit.xml and verdict.json
# into DIR (a CI artifact).
#
# The base is REF, or else the commit that last changed a baseline file (the build they were blessed
# from), or the bless before it where that commit is the one checked out (`blessed_base`). When the
# base's code differs from the working tree's, the gate builds the base beside the head and runs
# both at the quick tier in alternating processes ($AABENCH_GATE_PROCESSES a side, default 4, of
# $AABENCH_GATE_REPETITIONS rounds each, default 3), after one head process that measures quality
# and the sequences while the base builds. The alternating processes time alone (`--quality off`,
# where the base's build knows it) the modes the gate times (`aabench modes --tier quick
# --timed-by-gate`: the unstalled ones and one stalled); `aabench compare` then decides time with
# the process as the unit, per scene and pooled over the scenes. The scenes of a suspect time
# (regressed, or noisy with its interval above 0) are measured again in as many fresh processes a
# side, once, and decided on all the processes (`compare --confirm-runs`). Where the change cannot
# move a frame's time (`gate_strategy` in ci/lib.sh: only baselines, docs or tests changed, or only
# code that works on what the rounds left, such as the metric, compare or the report, or elsewhere
# only comments, blank lines and spacing), no base is built and no time is measured: one process
# measures quality and is compared with the baselines. Without a usable base (no git history, or a
# shallow clone), one run is compared with the baselines and time is gated only on the machine that
# blessed them.
#
# Writes summary.md, junit.xml, verdict.json and the HTML report into the first head run's
# folder. Exits with compare's code: 0 nothing regressed, 1 a regression (or the run compared
# less than its baselines hold), 2 an error, 3 a scene failed; else 4 where the command run
# alongside failed. With $GITHUB_STEP_SUMMARY set, the summary is appended to it.
# AABENCH_GATE_FAIL_ON=all|quality overrides `--fail-on auto`.
set -uo pipefail
invoked_from=$PWD
cd "$(dirname "$0")/.."
source ci/lib.sh

base_ref=""
shard_args=()
verdict_out=""
alongside=""
run_args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --base) base_ref=${2:?ci/gate.sh: --base needs a git revision}; shift 2 ;;
        --base=*) base_ref=${1#--base=}; shift ;;
        --shard) shard_args=(--shard "${2:?ci/gate.sh: --shard needs I/N}"); shift 2 ;;
        --shard=*) shard_args=(--shard "${1#--shard=}"); shift ;;
        --verdict-out) verdict_out=${2:?ci/gate.sh: --verdict-out needs a folder}; shift 2 ;;
        --verdict-out=*) verdict_out=${1#--verdict-out=}; shift ;;
        --alongside) alongside=${2:?ci/gate.sh: --alongside needs a command}; shift 2 ;;
        --alongside=*) alongside=${1#--alongside=}; shift ;;
        *) run_args+=("$1"); shift ;;
    esac
done
# A malformed shard fails here, once, before any set-up, build or process (aabench's own check,
# `plan::parse_shard`, would refuse it in every process after both builds).
if [ ${#shard_args[@]} -gt 0 ]; then
    shard=${shard_args[1]}
    if ! [[ $shard =~ ^([1-9][0-9]{0,8})/([1-9][0-9]{0,8})$ ]] || ((BASH_REMATCH[1] > BASH_REMATCH[2])); then
        echo "ci/gate.sh: --shard $shard: expected I/N with 1 ≤ I ≤ N, e.g. 2/4" >&2
        exit 2
    fi
fi
if [ -n "$verdict_out" ]; then
    # Relative to where the gate was started; an earlier gate's verdict must not outlive this one.
    case "$verdict_out" in /*) ;; *) verdict_out="$invoked_from/$verdict_out" ;; esac
    rm -f "$verdict_out/summary.md" "$verdict_out/junit.xml" "$verdict_out/verdict.json"
fi
processes=${AABENCH_GATE_PROCESSES:-4}
repetitions=${AABENCH_GATE_REPETITIONS:-3}
fail_on=${AABENCH_GATE_FAIL_ON:-auto}

build_aabench
gate_dir="$PWD/reports/gate-$(date -u +%Y%m%dT%H%M%SZ)-$$"
mkdir -p "$gate_dir/bin" || exit 2
head_bin="$gate_dir/bin/aabench-head"
cp "$bin" "$head_bin" || exit 2

# The base commit, or nothing when there is no git history to take it from.
resolve_base() {
    if [ -n "$base_ref" ]; then
        git rev-parse --verify --quiet "$base_ref^{commit}" || {
            echo "ci/gate.sh: --base $base_ref is no commit of this repository" >&2
            exit 2
        }
    else
        blessed_base
    fi
}
base=$(resolve_base) || exit 2

# alternate DIR ARGS...: $processes processes a side of `run --tier quick ARGS...`, the head's
# into DIR/head and the base's into DIR/base, in the order base head head base base head …, so
# that a drift of the machine over the job weighs on both builds alike. Each times the modes
# that both builds time ($timing_modes). A head process that exits non-zero sets run_code; a
# base process that does is only reported.
alternate() {
    local dir=$1
    shift
    for ((i = 1; i <= processes; i++)); do
        local order=(base head)
        if ((i % 2 == 0)); then order=(head base); fi
        for side in "${order[@]}"; do
            echo "ci/gate.sh: process $i of $processes, $side" >&2
            if [ "$side" = head ]; then
                "$head_bin" run --tier quick --repetitions "$repetitions" "${head_timing[@]}" "${timing_modes[@]}" \
                    --out "$dir/head" "$@"
                local code=$?
                if [ "$code" -ne 0 ] && [ "$run_code" -eq 0 ]; then run_code=$code; fi
            else
                (cd "$base_src" && "$gate_dir/bin/aabench-base" run --tier quick --repetitions "$repetitions" \
                    "${base_timing[@]}" "${timing_modes[@]}" --out "$dir/base" "$@") ||
                    echo "ci/gate.sh: a base process exited $?; compare uses the base runs that finished" >&2
            fi
        done
    done
}

# start_quality ARGS...: starts the head's process that measures every mode's quality and the
# sequences, which compare checks against the baselines, in the background (quality_pid, its
# output in $gate_dir/quality.log). It gives no time (where the base's processes time alone,
# or where nothing is timed), so it renders one round without a warm-up and needs no machine to
# itself: it runs beside the --alongside command and the base's build.
start_quality() {
    echo "ci/gate.sh: the head's quality process, which gives no time, in the background" >&2
    "$head_bin" run --tier quick --repetitions 1 --warmup 0 --sequences on --out "$gate_dir/head" "$@" \
        >"$gate_dir/quality.log" 2>&1 &
    quality_pid=$!
    # A gate that stops before it waits for the process (the base does not build) stops it too.
    trap 'kill "$quality_pid" 2>/dev/null' EXIT
}

# finish_quality: waits for the quality process, shows its output and sets run_code.
finish_quality() {
    wait "$quality_pid"
    run_code=$?
    trap - EXIT
    cat "$gate_dir/quality.log" >&2
}

# run_alongside: runs the --alongside command, if any, and sets alongside_code to its exit code.
alongside_code=0
run_alongside() {
    [ -n "$alongside" ] || return 0
    echo "ci/gate.sh: beside the work that gives no time: $alongside" >&2
    local began_alongside=$SECONDS
    bash -c "$alongside"
    alongside_code=$?
    echo "ci/gate.sh: '$alongside' exited $alongside_code after $((SECONDS - began_alongside)) s" >&2
}

# measure_quality ARGS...: against a base that measures quality in every process, the head's
# quality process is one of the timed ones: it runs alone, after the build, with the timing
# processes' rounds.
measure_quality() {
    echo "ci/gate.sh: the head's quality process, timed like the base's" >&2
    "$head_bin" run --tier quick --repetitions "$repetitions" --sequences on --out "$gate_dir/head" "$@"
    run_code=$?
}

# timed_by_both: sets timing_modes to `--modes LIST`, the modes of the quick tier that the gate
# times (`aabench modes --tier quick --timed-by-gate`) and the base build knows; to nothing
# (every mode) where the base cannot list its modes.
timed_by_both() {
    timing_modes=()
    local arg known
    for arg in "${run_args[@]}"; do
        case "$arg" in --modes | --modes=*) return 0 ;; esac
    done
    known=$("$gate_dir/bin/aabench-base" modes 2>/dev/null) || return 0
    local ids=()
    while read -r id; do
        if grep -qxF "  $id" <<<"$known"; then ids+=("$id"); fi
    done < <("$head_bin" modes --tier quick --timed-by-gate)
    if [ "${#ids[@]}" -gt 0 ]; then timing_modes=(--modes "$(IFS=,; echo "${ids[*]}")"); fi
}

# finished_runs DIR: sets finished to the run folders under DIR that hold a run.json.
finished_runs() {
    finished=()
    for run in "$1"/*/; do
        if [ -f "$run/run.json" ]; then finished+=("$run"); fi
    done
}

began=$(date +%s)
started=$began
strategy=$(gate_strategy "$base")
case $strategy in
    baselines) echo "ci/gate.sh: no base commit (no git history?): time is gated against the baselines only on the machine that blessed them" >&2 ;;
    unchanged) echo "ci/gate.sh: the code is the base's (${base:0:12}): time cannot have moved and is not measured" >&2 ;;
    untimed)
        echo "ci/gate.sh: no code that can move a frame's time changed since the base (${base:0:12}), comments, blank lines and spacing aside, so time is not measured; what changed:" >&2
        git diff --name-only "$base" -- "${binary_paths[@]}" | sed 's/^/    /' >&2
        ;;
esac

if [ "$strategy" != ab ]; then
    # Without a base, one run's 25 rounds are gated against the baselines of the machine that
    # blessed them, alone. Where the change cannot have moved a frame's time, a timing gate could
    # only find noise: one process measures quality and the sequences, in one round without a
    # warm-up (the A/B gate's quality process), and compare compares no time.
    if [ "$strategy" = baselines ]; then
        run_alongside
        "$head_bin" run --tier quick --repetitions 25 "${shard_args[@]}" --out "$gate_dir/head" "${run_args[@]}"
        run_code=$?
    else
        [ "$fail_on" = auto ] && fail_on=quality
        start_quality "${shard_args[@]}" "${run_args[@]}"
        run_alongside
        finish_quality
    fi
    head_runs=("$gate_dir"/head/*/)
    base_args=()
else
    # The base is built from its own tree into a target folder of its own: cargo names a
    # workspace's artifacts by their path inside the workspace, so two trees sharing one target
    # folder overwrite each other's binaries and each may then look up to date. The folder is
    # kept, so a later gate on this machine compiles only the workspace's own crates again. The
    # tree is extracted with fresh times (`tar -m`): git archive stamps files with the commit's
    # time, which can be older than a previous gate's build of another base, and cargo would
    # then take that build's binary as up to date.
    base_src="$gate_dir/base-src"
    base_target="$PWD/target/gate-base"
    mkdir -p "$base_src" && git archive "$base" | tar -x -m -C "$base_src" || exit 2
    # Base binaries are kept by commit and toolchain ($AABENCH_GATE_BASE_CACHE, default
    # target/gate-base/bins: a CI cache of that folder keeps them between jobs), so a second
    # gate against the same base builds nothing.
    toolchain=$( (rustc -vV && echo "${RUSTFLAGS:-}") | sha256sum | cut -c1-12)
    cached_base="${AABENCH_GATE_BASE_CACHE:-$base_target/bins}/$base-$toolchain/aabench"
    start_quality "${shard_args[@]}" "${run_args[@]}"
    run_alongside
    if [ -x "$cached_base" ]; then
        echo "ci/gate.sh: the base ${base:0:12}, built before: $cached_base" >&2
    else
        echo "ci/gate.sh: building the base ${base:0:12} to gate time against it on this machine" >&2
        # A first base build starts from a copy of the head's: the dependencies (most of a clean
        # build) are the same crates built alike and stay fresh, while the workspace's crates,
        # whose extracted sources are newer than anything built, compile again.
        if [ ! -d "$base_target/release" ] && [ -d target/release ]; then
            mkdir -p "$base_target" && cp -a --reflink=auto target/release "$base_target/release.tmp-$$" &&
                mv "$base_target/release.tmp-$$" "$base_target/release" ||
                rm -rf "$base_target/release.tmp-$$"
        fi
        # The dependencies are built as the head's are, without line tables (debug info does
        # not change code), so that the copy of the head's build serves a base from before
        # that setting instead of building every dependency again.
        (cd "$base_src" && CARGO_TARGET_DIR="$base_target" cargo build --release --locked -p aabench \
            --config 'profile.release.package."*".debug=false') || {
            echo "ci/gate.sh: the base ${base:0:12} does not build" >&2
            exit 2
        }
        # Copied in under a temporary name and renamed, so that a killed gate leaves no half binary.
        mkdir -p "$(dirname "$cached_base")" &&
            cp "$base_target/release/aabench" "$cached_base.tmp-$$" &&
            mv "$cached_base.tmp-$$" "$cached_base" || exit 2
    fi
    cp "$cached_base" "$gate_dir/bin/aabench-base" || exit 2
    started=$(date +%s)
    finish_quality
    # The timing processes time alone where the base's build can (`--quality off`); else both
    # sides measure quality in every process and only leave out the sequences where the base
    # renders them, so that the two builds do the same work between their timed rounds, and the
    # head's quality process is measured again, alone and timed.
    base_timing=()
    head_timing=(--sequences off)
    base_help=$("$gate_dir/bin/aabench-base" run --help)
    if grep -q -- --quality <<<"$base_help"; then
        base_timing=(--quality off)
        head_timing=(--quality off)
    else
        if grep -q -- --sequences <<<"$base_help"; then base_timing=(--sequences off); fi
        rm -rf "$gate_dir/head"
        measure_quality "${shard_args[@]}" "${run_args[@]}"
    fi
    timed_by_both
    alternate "$gate_dir" "${shard_args[@]}" "${run_args[@]}"
    head_runs=("$gate_dir"/head/*/)
    finished_runs "$gate_dir/base"
    base_args=(--base-runs "${finished[@]}")
    if [ "${#finished[@]}" -eq 0 ]; then base_args=(); fi
fi
if [ ! -f "${head_runs[0]}/run.json" ]; then
    echo "ci/gate.sh: the run wrote nothing (exit $run_code)" >&2
    exit 2
fi
run_dir=${head_runs[0]%/}

compare=("$head_bin" compare "${head_runs[@]}" "${base_args[@]}" --baseline baselines --out "$run_dir" --fail-on "$fail_on")
"${compare[@]}"
code=$?
# A suspect time against the base (regressed, or noisy with its interval above 0, per scene or
# pooled over the scenes) is measured again in as many fresh processes a side, of its scenes
# only, and decided once more: regressed only where all the processes together clear the
# tolerance and the fresh ones alone estimate it past the tolerance too. One false alarm among a
# gate's two thousand time checks is no rare event, the same one found again by fresh processes
# is; and a slowdown near the tolerance, noisy on four processes a side, is decided on eight.
if [ "$strategy" = ab ] && [ "$code" -le 1 ] && [ -s "$run_dir/to-confirm.txt" ]; then
    mapfile -t confirm_scenes <"$run_dir/to-confirm.txt"
    echo "ci/gate.sh: time suspect in ${confirm_scenes[*]}: measuring again in fresh processes" >&2
    alternate "$gate_dir/confirm" "${confirm_scenes[@]}"
    finished_runs "$gate_dir/confirm/base"
    confirm_base=("${finished[@]}")
    finished_runs "$gate_dir/confirm/head"
    if [ "${#finished[@]}" -gt 0 ] && [ "${#confirm_base[@]}" -gt 0 ]; then
        "${compare[@]}" --confirm-runs "${finished[@]}" --confirm-base-runs "${confirm_base[@]}"
        code=$?
    else
        echo "ci/gate.sh: the fresh processes wrote nothing: the regressions stand" >&2
    fi
fi
# A scene that failed already fails compare; this keeps a run that went wrong otherwise from
# passing unnoticed.
if [ "$code" -eq 0 ] && [ "$run_code" -ne 0 ]; then code=$run_code; fi
if [ "$alongside_code" -ne 0 ]; then
    echo "ci/gate.sh: '$alongside' failed (exit $alongside_code), so the gate fails" >&2
    if [ "$code" -eq 0 ]; then code=4; fi
fi
"$head_bin" report "$run_dir" >/dev/null || echo "ci/gate.sh: the HTML report could not be written" >&2
if [ -n "$verdict_out" ]; then
    mkdir -p "$verdict_out" && cp "$run_dir/summary.md" "$run_dir/junit.xml" "$run_dir/verdict.json" "$verdict_out/" ||
        echo "ci/gate.sh: the verdict could not be copied to $verdict_out" >&2
fi
if [ -n "${GITHUB_STEP_SUMMARY:-}" ] && [ -f "$run_dir/summary.md" ]; then
    cat "$run_dir/summary.md" >>"$GITHUB_STEP_SUMMARY"
fi
echo "ci/gate.sh: $strategy gate, $(($(date +%s) - started)) s after the builds, $(($(date +%s) - began)) s with the base's" >&2
echo "ci/gate.sh: $run_dir/summary.md, junit.xml, verdict.json, index.html (exit $code)" >&2
exit "$code"
