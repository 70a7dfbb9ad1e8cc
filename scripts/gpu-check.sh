#!/usr/bin/env bash
# Checks a real GPU with binaries built elsewhere: the release test binaries of the workspace and
# every bin (the CLI tests run them). Two steps, for a GPU machine without a Rust toolchain:
#
#   scripts/gpu-check.sh pack BUNDLE            # here: build in release, write BUNDLE (.tar.xz)
#   scripts/gpu-check.sh run BUNDLE OUT [LOOPS] # there, from the repository root: unpack, then
#                                               # run every test binary (LOOPS times, default 1),
#                                               # `trgs bench`, the GPU's busy share of a step at 1M
#                                               # Gaussians and 1600x1200 (`bench --scale`), and
#                                               # log everything under OUT
#   scripts/gpu-check.sh hunt BUNDLE OUT SECONDS TEST...
#                                               # there: run the named test binaries in turn for
#                                               # SECONDS; a run still going after HUNT_AFTER
#                                               # seconds (default 25) is a hang: record the GPU's
#                                               # load, every thread's kernel wait and the code
#                                               # addresses of the threads on the CPU or blocked
#                                               # on a lock (thread_pcs), then kill it
#
# Test binaries find their fixtures through the absolute path of the checkout they were built
# in; `run` links that path to the current checkout when it is missing. Every test binary runs
# with poison-filled buffers (TRGS_POISON_BUFFERS=1), 8 test threads and a time limit, and logs
# with --nocapture (time limit: GPU_CHECK_TIMEOUT seconds, default 300). The summary lists every
# run that failed or timed out, with the tests of that run that never reported.
set -uo pipefail
cd "$(dirname "$0")/.."

usage() {
    sed -n '2,23p' "$0" >&2
    exit 2
}

pack() {
    local bundle=$1
    set -e
    cargo build --release --locked --bins
    cargo test --workspace --release --locked --no-run --message-format=json 2>/dev/null |
        python3 -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("profile", {}).get("test") and m.get("executable"):
        print(m["executable"])
' | sed "s|^$PWD/||" | grep -v viewer_window >target/release/gpu-check-tests.txt
    echo "$PWD" >target/release/gpu-check-root.txt
    # The thread sampler for `hunt`, static so that it needs nothing on the GPU machine.
    local sampler=()
    if command -v gcc >/dev/null; then
        gcc -O1 -static -o target/release/thread_pcs scripts/thread_pcs.c
        sampler=(target/release/thread_pcs)
    else
        echo "no gcc: the bundle has no thread_pcs, and hunt records kernel waits only" >&2
    fi
    tar cf - target/release/gpu-check-tests.txt target/release/gpu-check-root.txt \
        $(cat target/release/gpu-check-tests.txt) "${sampler[@]}" \
        target/release/{trgs,train,viewer} |
        xz -T0 -6 >"$bundle"
    echo "wrote $bundle ($(wc -l <target/release/gpu-check-tests.txt) test binaries)"
}

# Unpack BUNDLE and make the test binaries' fixture paths resolve.
unpack() {
    tar xJf "$1"
    local root
    root=$(cat target/release/gpu-check-root.txt)
    if [ ! -e "$root" ]; then
        mkdir -p "$(dirname "$root")" && ln -s "$PWD" "$root"
    fi
}

run() {
    local bundle=$1 out=$2 loops=${3:-1}
    mkdir -p "$out"
    unpack "$bundle"
    : >"$out/summary.txt"
    for i in $(seq 1 "$loops"); do
        while read -r t; do
            local name log
            name=$(basename "$t")
            log="$out/${name%-*}.log"
            echo "=== run $i" >>"$log"
            TRGS_POISON_BUFFERS=1 timeout "${GPU_CHECK_TIMEOUT:-300}" "./$t" --test-threads=8 --nocapture >>"$log" 2>&1
            local rc=$?
            if [ "$rc" -ne 0 ]; then
                # The tests of this run that never reported: the hung ones, on a timeout.
                local unfinished
                unfinished=$("./$t" --list 2>/dev/null | sed -n 's/: test$//p' | while read -r test; do
                    sed -n "/^=== run $i\$/,\$p" "$log" | grep -q "^test $test \.\.\. " || echo "$test"
                done | tr '\n' ' ')
                echo "run $i: ${name%-*} rc=$rc (124: timed out); unfinished: ${unfinished:-none}" |
                    tee -a "$out/summary.txt"
            fi
        done <target/release/gpu-check-tests.txt
    done
    ./target/release/trgs bench --write "$out/bench.md" >"$out/bench.log" 2>&1 ||
        echo "bench rc=$?" | tee -a "$out/summary.txt"
    # The steady-state step at 1M Gaussians and 1600x1200, and the share of it the GPU is busy.
    ./target/release/trgs bench --scale --scale-sizes 1600x1200 --scale-gaussians 1000000 --reps 20 \
        >"$out/busy.log" 2>&1 || echo "bench --scale rc=$?" | tee -a "$out/summary.txt"
    echo "$(wc -l <"$out/summary.txt") failed runs; logs in $out"
}

# Record where the threads of hung process $1 are, into file $2.
record_hang() {
    local pid=$1 out=$2
    nvidia-smi --query-gpu=utilization.gpu,clocks.sm,power.draw --format=csv >>"$out" 2>&1
    local spinning=()
    for d in /proc/"$pid"/task/*; do
        local wchan
        wchan=$(cat "$d/wchan" 2>/dev/null)
        echo "thread $(basename "$d") $(cat "$d/comm" 2>/dev/null): wchan ${wchan:-?}" >>"$out"
        # On the CPU (wchan 0) or waiting for a lock (priority-inheritance futexes).
        case "$wchan" in 0 | rt_mutex_schedule) spinning+=("$(basename "$d")") ;; esac
    done
    if [ ${#spinning[@]} -gt 0 ] && [ -x target/release/thread_pcs ]; then
        ./target/release/thread_pcs "$pid" "${spinning[@]}" >>"$out" 2>&1
    fi
}

hunt() {
    local bundle=$1 out=$2 seconds=$3
    shift 3
    mkdir -p "$out"
    unpack "$bundle"
    # A name may match several binaries (gpu_failures is in two crates): each one runs.
    local name binaries=()
    for name in "$@"; do
        mapfile -t -O "${#binaries[@]}" binaries < <(grep "/$name-" target/release/gpu-check-tests.txt)
    done
    [ ${#binaries[@]} -gt 0 ] || { echo "no test binary named $*" >&2; return 2; }
    local start runs=0 hangs=0 t pid
    start=$(date +%s)
    while [ $(($(date +%s) - start)) -lt "$seconds" ]; do
        for t in "${binaries[@]}"; do
            name=$(basename "$t")
            name=${name%-*}
            runs=$((runs + 1))
            echo "=== run $runs" >>"$out/$name.log"
            TRGS_POISON_BUFFERS=1 "./$t" --test-threads=8 >>"$out/$name.log" 2>&1 &
            pid=$!
            for _ in $(seq 1 "${HUNT_AFTER:-25}"); do
                sleep 1
                kill -0 "$pid" 2>/dev/null || break
            done
            if kill -0 "$pid" 2>/dev/null; then
                hangs=$((hangs + 1))
                echo "run $runs: $name hung" | tee -a "$out/summary.txt"
                record_hang "$pid" "$out/hang_${runs}_$name.txt"
                kill -9 "$pid" 2>/dev/null
            fi
            wait "$pid" 2>/dev/null
        done
    done
    echo "$hangs hangs in $runs runs; logs in $out" | tee -a "$out/summary.txt"
}

case "${1:-}" in
pack) [ $# -eq 2 ] || usage; pack "$2" ;;
run) [ $# -ge 3 ] || usage; run "$2" "$3" "${4:-1}" ;;
hunt) [ $# -ge 5 ] || usage; hunt "$2" "$3" "$4" "${@:5}" ;;
*) usage ;;
esac
