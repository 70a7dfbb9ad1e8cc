#!/usr/bin/env bash
# trgs (plain 3DGS) against Brush on a GPU machine that has neither a Rust toolchain nor the
# network: the real-photos comparison of docs/captures.md at 1600 px. Two steps:
#
#   scripts/gpu-peers.sh pack BUNDLE BRUSH_CLI SCENE...
#       here: BUNDLE (.tar.xz) holds the release `train`, the stripped BRUSH_CLI (built outside
#       the repo with ../shared/peers/brush/build.sh), brush_scene.py from beside that script, and
#       each SCENE folder's images/ and sparse/ (COLMAP's database stays behind)
#   scripts/gpu-peers.sh run BUNDLE OUT T1 [T2]
#       there, from the repository root:
#       A  every scene at 1600 px on the 30000-step schedule, trgs and Brush side by side, all
#          at once, evaluated every 1000 steps and stopped after T1 seconds;
#       B  each SCENE:DOWNSCALE of $SMALL (e.g. "monstree:3.3333") at 480 px for 2000 steps,
#          beside A, to the end or T1;
#       C  the scene $ALONE (default: the first) at 1600 px, the pair with nothing else on the
#          GPU, for T2 seconds (default 80; 0 skips it);
#       then OUT/results.tgz: every log, log.jsonl and metrics.json (no models, no renders).
#       $ALSO (e.g. "--grow-fraction 0.25") adds to A a second trgs run of each scene with those
#       flags (tag 1600also); NO_BRUSH=1 leaves Brush out of A and C, where its curves of the
#       same bundle's scenes are already known.
#
# Brush is given the same scene folder through brush_scene.py (its every-8th split is trgs's
# test_views.txt), `--max-resolution` the size trgs trains at, and seed 42; it logs "Eval iter N:
# PSNR p, ssim s" and "Refine iter N, K splats" with timestamps (RUST_LOG=info). A run stopped by
# its time limit leaves its evaluations in its log; trgs's log.jsonl has every step's time and
# Gaussian count.
set -uo pipefail
cd "$(dirname "$0")/.."

usage() {
    sed -n '2,25p' "$0" >&2
    exit 2
}

pack() {
    local bundle=$1 brush=$2
    shift 2
    [ $# -gt 0 ] || usage
    set -e
    local stage
    stage=$(mktemp -d)
    trap "rm -rf '$stage'" EXIT
    cargo build --release --locked --bin train
    cp target/release/train "$stage/"
    cp "$brush" "$stage/brush-cli"
    strip "$stage/brush-cli"
    cp ../shared/peers/brush/brush_scene.py "$stage/"
    for scene in "$@"; do
        local name
        name=$(basename "$scene")
        [ -d "$scene/sparse" ] || { echo "$scene: not a scene folder (no sparse/)" >&2; exit 1; }
        mkdir -p "$stage/scenes/$name"
        cp -r "$scene/images" "$scene/sparse" "$stage/scenes/$name/"
    done
    tar cf - -C "$stage" . | xz -T0 -9 >"$bundle.part"
    mv "$bundle.part" "$bundle"
    echo "wrote $bundle ($(du -h "$bundle" | cut -f1), scenes: $*)"
}

# One trgs run and one Brush run of SCENE, named by TAG: trgs with TRGS_SIZE (empty: its
# default, 1600 px on the longer side; or "--downscale F"), Brush at --max-resolution
# BRUSH_SIZE; STEPS on the schedule, evaluated every EVAL steps, each stopped after SECONDS.
pair() {
    local tag=$1 scene=$2 trgs_size=$3 brush_size=$4 steps=$5 eval=$6 seconds=$7 work=$8
    trgs "$tag" "$scene" "$trgs_size" "$steps" "$eval" "$seconds" "$work"
    [ "${NO_BRUSH:-0}" = 1 ] && [ "$tag" != 480 ] && return
    RUST_LOG=info timeout -s INT "$seconds" ./brush-cli "bscenes/$scene" \
        --total-train-iters "$steps" --eval-split-every 8 --eval-every "$eval" \
        --export-every "$steps" --max-resolution "$brush_size" --seed 42 \
        --export-path "$work/b${tag}_$scene" >"$work/b${tag}_$scene.log" 2>&1 &
}

# The trgs half of a pair; FLAGS (word-split) go on its command line.
trgs() {
    local tag=$1 scene=$2 flags=$3 steps=$4 eval=$5 seconds=$6 work=$7
    timeout -s INT "$seconds" ./train --data "scenes/$scene" $flags --iterations "$steps" \
        --eval-every "$eval" --checkpoint-every "$steps" --out "$work/t${tag}_$scene" \
        >"$work/t${tag}_$scene.log" 2>&1 &
}

run() {
    local bundle=$1 out=$2 t1=$3 t2=${4:-80}
    local work unpacked
    work=$(mktemp -d)
    unpacked=$(mktemp -d)
    trap "rm -rf '$work' '$unpacked'" EXIT
    mkdir -p "$out" && out=$(cd "$out" && pwd) || exit 3
    tar xJf "$bundle" -C "$unpacked" || exit 3
    cd "$unpacked" || exit 3
    command -v nvidia-smi >/dev/null &&
        nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
    ./train --version || exit 4
    ./brush-cli --help >/dev/null 2>&1 || { echo "brush-cli does not start" >&2; exit 4; }
    local scenes
    scenes=$(ls scenes)
    for s in $scenes; do
        python3 brush_scene.py "scenes/$s" "bscenes/$s" >/dev/null || exit 5
    done
    local start
    start=$(date +%s)
    for s in $scenes; do
        pair 1600 "$s" "" 1600 30000 1000 "$t1" "$work"
        [ -n "${ALSO:-}" ] && trgs 1600also "$s" "$ALSO" 30000 1000 "$t1" "$work"
    done
    for item in ${SMALL:-}; do
        pair 480 "${item%%:*}" "--downscale ${item#*:}" 480 2000 2000 "$t1" "$work"
    done
    while [ $(($(date +%s) - start)) -lt $((t1 + 20)) ] && [ -n "$(jobs -r)" ]; do
        nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv,noheader \
            >>"$work/gpu.log" 2>&1
        sleep 10
    done
    wait
    echo "A and B: $(($(date +%s) - start)) s"
    if [ "$t2" -gt 0 ]; then
        local alone=${ALONE:-$(echo "$scenes" | head -1)}
        pair 1600alone "$alone" "" 1600 30000 30000 "$t2" "$work"
        wait
        echo "C: $(($(date +%s) - start)) s in all"
    fi
    tar czf "$out/results.tgz" -C "$work" --exclude='*.ply' --exclude='*.trgs' \
        --exclude='*.png' .
    ls -la "$out"
}

case "${1:-}" in
pack) [ $# -ge 4 ] || usage; shift; pack "$@" ;;
run) [ $# -ge 4 ] || usage; shift; run "$@" ;;
*) usage ;;
esac
