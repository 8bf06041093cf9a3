#!/usr/bin/env bash
# Shared by ci/gate.sh and ci/nightly.sh: set up, build, and run aabench into a fresh folder.

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
