#!/usr/bin/env bash
# The two GPU measurements of the scale work in one command that fits a short loan of a GPU
# machine (docs/BENCHMARKS.md, "The GPU measurements of the scale work"): run it there from the
# repository root with the release `trgs` and `train` built here and carried along (the
# machine needs no Rust toolchain).
#
#   scripts/gpu-bars.sh OUT [SECONDS] [PARTS]
#
# PARTS is `both` (default), `busy` or `fixture`: a loan with room for two calls gives the
# fixture a whole call of its own (`busy` first, then `fixture` with up to 590 s).
#
# 1. The GPU's busy share of a pipelined training step at 1M Gaussians and 1600x1200
#    (`bench --scale`), given at most a third of SECONDS when both parts run: OUT/busy.log.
# 2. The scale fixture (the built-in scene, 200 + 8 photos of 1280x960) trained for 30000 steps,
#    or for as long as SECONDS (default 570, the whole command) leaves: OUT/fixture.log, the
#    run's log.jsonl (gzipped) and metrics.json when it finishes.
# Both logs end in OUT/summary.txt: steps reached, the step rate over the last 1000 steps and
# the wall time that rate projects for the whole run, where a step's time went (recording,
# waiting for the GPU, maintenance), each evaluation's test PSNR.
#
# BARS_BUSY_ARGS and BARS_FIXTURE_ARGS replace the two commands' size arguments (a smoke run on
# lavapipe: BARS_BUSY_ARGS="--scale-sizes 256x192 --scale-gaussians 20000 --reps 2"
# BARS_FIXTURE_ARGS="--demo-size 256x192 --demo-views 40 --iterations 300 --eval-every 100").
set -uo pipefail
cd "$(dirname "$0")/.."

[ $# -ge 1 ] || { sed -n '2,23p' "$0" >&2; exit 2; }
out=$1
budget=${2:-570}
parts=${3:-both}
case $parts in both | busy | fixture) ;; *)
    echo "PARTS must be both, busy or fixture, not '$parts'" >&2
    exit 2
    ;;
esac
deadline=$((SECONDS + budget))
# The fixture and its run: outside OUT, whose files are copied back.
run_dir=/tmp/gpu-bars-fixture
mkdir -p "$out"
rm -rf "$run_dir"

# shellcheck disable=SC2086 # the overrides are argument lists
busy_args=(${BARS_BUSY_ARGS:---scale-sizes 1600x1200 --scale-gaussians 1000000 --reps 20})
# shellcheck disable=SC2086
fixture_args=(${BARS_FIXTURE_ARGS:---demo-size 1280x960 --demo-views 200 --iterations 30000 \
    --eval-every 2500})

# The run's length, for the projection: the value after --iterations.
steps=30000
for ((i = 0; i + 1 < ${#fixture_args[@]}; i++)); do
    [ "${fixture_args[i]}" = --iterations ] && steps=${fixture_args[i + 1]}
done

: >"$out/summary.txt"
if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv >>"$out/summary.txt" 2>&1
fi

# The busy share gets at most a third of the budget: the fixture's run is the longer measurement.
if [ "$parts" != fixture ]; then
    busy_budget=$budget
    [ "$parts" = both ] && busy_budget=$((budget / 3))
    timeout "$busy_budget" ./target/release/trgs bench --scale "${busy_args[@]}" >"$out/busy.log" 2>&1
    echo "bench --scale rc=$? (124: timed out)" >>"$out/busy.log"
fi

# SIGINT, then SIGKILL 10 s later: log.jsonl is written line by line, so the steps run stay.
left=$((deadline - SECONDS - 20))
if [ "$parts" = busy ]; then
    :
elif [ "$left" -gt 30 ]; then
    timeout -k 10 -s INT "$left" ./target/release/train "${fixture_args[@]}" --out "$run_dir" \
        >"$out/fixture.log" 2>&1
    echo "train rc=$? (124: stopped at the time limit)" >>"$out/fixture.log"
else
    echo "no time left for the fixture's run" >>"$out/fixture.log"
fi
[ -f "$run_dir/log.jsonl" ] && gzip -c "$run_dir/log.jsonl" >"$out/fixture-log.jsonl.gz"
[ -f "$run_dir/metrics.json" ] && cp "$run_dir/metrics.json" "$out/"

{
    if [ "$parts" != fixture ]; then
        grep -m1 "^adapter:" "$out/busy.log"
        sed -n '/^| image/,$p' "$out/busy.log" | grep "^|" || echo "bench --scale: no table"
    fi
    [ "$parts" = busy ] || python3 - "$run_dir/log.jsonl" "$steps" <<'EOF'
import json, statistics, sys
path, target = sys.argv[1], int(sys.argv[2])
steps, evals = [], []
try:
    for line in open(path):
        d = json.loads(line)
        if "eval" in d:
            evals.append(d["eval"])
        elif "step" in d:
            steps.append(d)
except (OSError, ValueError) as e:
    print(f"fixture: no log ({e})")
    sys.exit(0)
if not steps:
    print("fixture: no step logged")
    sys.exit(0)
last = steps[-1]
tail = steps[-1000:]
rate = (tail[-1]["seconds"] - tail[0]["seconds"]) / max(len(tail) - 1, 1)
print(f"fixture: {last['step']} steps in {last['seconds']:.0f} s of training, "
      f"{last['gaussians']} Gaussians, {sum(s['skipped'] for s in steps)} skipped")
print(f"fixture: {1000 * rate:.1f} ms a step over the last {len(tail)} steps; "
      f"{target} steps at that rate: {last['seconds'] + rate * (target - last['step']):.0f} s")
# On a GPU a step's phases are recorded without waiting (records_while_busy), so render, loss,
# backward and adam are the CPU's recording time and readback is mostly the wait for the GPU:
# a step waiting there is a step the GPU, not the CPU, set the pace of.
med = lambda key: statistics.median(s["ms"].get(key, 0.0) for s in tail)
record = statistics.median(sum(s["ms"].get(k, 0.0) for k in ("render", "loss", "backward", "adam"))
                           for s in tail)
waits = sum(s.get("record_waits", 0) for s in tail)
print(f"fixture: median ms a step over the same steps: recording {record:.2f} ({waits} waits for "
      f"the GPU in it over the {len(tail)} steps), reading back (waiting for the GPU) "
      f"{med('readback'):.2f}, maintenance {med('densify'):.2f}")
print(f"fixture: peak RAM {last['peak_ram_bytes'] / 2**30:.2f} GiB, "
      f"GPU buffers {last['gpu_bytes'] / 2**30:.2f} GiB, median keys "
      f"{statistics.median(s['keys'] for s in tail):.0f}")
for e in evals:
    print(f"fixture: step {e['step']}: test PSNR {e['psnr']:.2f} dB, SSIM {e['ssim']:.4f}")
EOF
} >>"$out/summary.txt" 2>&1
cat "$out/summary.txt"
