#!/usr/bin/env bash
# Shared by ci/gate.sh and ci/nightly.sh: set up, build, and run aabench into a fresh folder; and
# which commit the gate times against and what of a change can move a frame's time, which decide
# how the gate measures it.

# Sets up the machine and builds the release binary; exits 2 on failure.
build_aabench() {
    ci/setup.sh || exit 2
    export NODEVICE_SELECT=1
    cargo build --release --locked -p aabench || exit 2
    bin=target/release/aabench
}

# run_fresh PREFIX ARGS...: runs `aabench run ARGS...` into a new reports/PREFIX-<time>-<pid>
# folder, so the run is the only one in it, and sets run_dir (exits 2 if nothing was written)
# and run_code.
run_fresh() {
    local prefix=$1
    shift
    local out="reports/$prefix-$(date -u +%Y%m%dT%H%M%SZ)-$$"
    "$bin" run --out "$out" "$@"
    run_code=$?
    run_dir=$(find "$out" -mindepth 1 -maxdepth 1 -type d | head -n 1)
    if [ -z "$run_dir" ]; then
        echo "ci: the run wrote nothing (exit $run_code)" >&2
        exit 2
    fi
}

# blessed_base: the commit the gate times against unless told another, the last that changed a
# baseline file (a README or a note beside them is no bless): the build the baselines were blessed
# from. Where that is the commit checked out (CI on a commit that re-blessed), its code would be
# its own base and never timed, so the bless before it is the base: a change that moves images
# is timed like any other. Along first parents, so that a pull request's merge commit that
# re-blesses is that commit, not the branch's bless. Nothing where there is no such commit or no
# whole history to find it in (a shallow clone's oldest commit seems to add every file).
blessed_base() {
    local baselines=':(glob)baselines/**/*.json'
    local last
    if [ "$(git rev-parse --is-shallow-repository 2>/dev/null)" != false ]; then return 0; fi
    last=$(git log -1 --first-parent --format=%H -- "$baselines" 2>/dev/null || true)
    if [ -n "$last" ] && [ "$last" = "$(git rev-parse --verify --quiet HEAD)" ]; then
        git log -1 --first-parent --format=%H HEAD^ -- "$baselines" 2>/dev/null || true
    else
        echo "$last"
    fi
}

# What cannot change the binary: the baselines themselves, the documentation, the CI workflows
# and lint tools, and the crates' tests and benchmarks.
binary_paths=(. ':(exclude)baselines' ':(exclude)*.md' ':(exclude)docs' ':(exclude).github' ':(exclude)ci/lint'
    ':(exclude)*/tests/*' ':(exclude)*/tests.rs' ':(exclude)*/benches/*')
# What is code but cannot change a frame's time: the metric crate; the runner's rooms that work
# on what the rounds left (the measures of images, the record, the baselines, compare, the
# report, the HTML markup) and its commands other than `run`; and the scripts that drive the
# gate, the suite, the nightly and the tests. A change confined to them can move a score or a
# verdict, which the quality checks and the tests see, but not what a mode costs. What renders
# or times a frame stays: the renderer and its shaders, the scenes, the runner's manifest, plan,
# run, files and `run` command, the manifests of the crates and the lock file, the build and
# set-up scripts.
timing_paths=("${binary_paths[@]}" ':(exclude)cvvdp' ':(exclude)runner/src/measure'
    ':(exclude)runner/src/record' ':(exclude)runner/src/baseline' ':(exclude)runner/src/compare'
    ':(exclude)runner/src/report' ':(exclude)runner/src/files/markup.rs'
    ':(exclude)runner/src/cli/bless.rs' ':(exclude)runner/src/cli/compare.rs' ':(exclude)runner/src/cli/inspect.rs'
    ':(exclude)runner/src/cli/merge.rs' ':(exclude)runner/src/cli/report.rs'
    ':(exclude)ci/gate.sh' ':(exclude)ci/suite.sh' ':(exclude)ci/nightly.sh' ':(exclude)ci/test.sh'
    ':(exclude)ci/injections' ':(exclude).ci')

# A line that is only a comment: `//` (Rust, WGSL), or `#` then a space or the line's end (TOML,
# shell), which no Rust attribute (`#[`, `#![`) and no shebang (`#!`) is; or a blank line (git
# drops a block of changed lines only where every line matches, and a comment is often added
# with a blank line before it).
comment_line=$'^[[:space:]]*(//|#([[:space:]]|$))|^[[:blank:]\r]*\n'
# A change whose every changed line is a comment, blank or only respaced (more or less space
# where there was some: `"a b"` to `"ab"` is a change) renders and times every frame as the
# base does (the binary differs only in the line numbers its panics name).
code_only=(--ignore-space-change --ignore-blank-lines --ignore-matching-lines="$comment_line")

# gate_strategy BASE: how the gate measures time against the commit BASE (empty where there is
# no history), from what the working tree changed since it:
#   baselines  no base: one run is gated against the baselines, time only on the machine that
#              blessed them;
#   unchanged  the binary is the base's: time cannot have moved;
#   untimed    code changed, none of it code that can move a frame's time (comments, blank
#              lines and spacing do not count);
#   ab         the head and the base are built and timed against each other.
gate_strategy() {
    if [ -z "$1" ]; then
        echo baselines
    elif git diff --quiet "$1" -- "${binary_paths[@]}"; then
        echo unchanged
    elif git diff --quiet "${code_only[@]}" "$1" -- "${timing_paths[@]}"; then
        echo untimed
    else
        echo ab
    fi
}
