#!/usr/bin/env bash
# Checks a real GPU with binaries built elsewhere: the release test binaries of the workspace and
# every bin (the CLI tests run them). Two steps, for a GPU machine without a Rust toolchain:
#
#   scripts/gpu-check.sh pack BUNDLE            # here: build in release, write BUNDLE (.tar.xz)
#   scripts/gpu-check.sh run BUNDLE OUT [LOOPS] # there, from the repository root: unpack, then
#                                               # run every test binary (LOOPS times, default 1),
#                                               # `bench`, and log everything under OUT
#
# Test binaries find their fixtures through the absolute path of the checkout they were built
# in; `run` links that path to the current checkout when it is missing. Every test binary runs
# with poison-filled buffers (TRGS_POISON_BUFFERS=1), 8 test threads and a time limit, and logs
# with --nocapture (time limit: GPU_CHECK_TIMEOUT seconds, default 300). The summary lists every
# run that failed or timed out, with the tests of that run that never reported.
set -uo pipefail
cd "$(dirname "$0")/.."

usage() {
    sed -n '2,14p' "$0" >&2
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
' | sed "s|^$PWD/||" | grep -v xvfb_screenshot >target/release/gpu-check-tests.txt
    echo "$PWD" >target/release/gpu-check-root.txt
    tar cf - target/release/gpu-check-tests.txt target/release/gpu-check-root.txt \
        $(cat target/release/gpu-check-tests.txt) target/release/{bench,train,render,eval,convert,report,viewer} |
        xz -T0 -6 >"$bundle"
    echo "wrote $bundle ($(wc -l <target/release/gpu-check-tests.txt) test binaries)"
}

run() {
    local bundle=$1 out=$2 loops=${3:-1}
    mkdir -p "$out"
    tar xJf "$bundle"
    local root
    root=$(cat target/release/gpu-check-root.txt)
    if [ ! -e "$root" ]; then
        mkdir -p "$(dirname "$root")" && ln -s "$PWD" "$root"
    fi
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
    ./target/release/bench --write "$out/bench.md" >"$out/bench.log" 2>&1 ||
        echo "bench rc=$?" | tee -a "$out/summary.txt"
    echo "$(wc -l <"$out/summary.txt") failed runs; logs in $out"
}

case "${1:-}" in
pack) [ $# -eq 2 ] || usage; pack "$2" ;;
run) [ $# -ge 3 ] || usage; run "$2" "$3" "${4:-1}" ;;
*) usage ;;
esac
