#!/usr/bin/env bash
# Objects cut off by the frame in the encoders' input (issue 12; results/cut_inputs.md): two `small` runs from
# scratch, side by side, one core each, on part_edges.sh's 13,000-step schedule (whose preset runs reproduce
# shape_pooling.sh's `keypoints` runs exactly, so the preset's rows are those runs'), each choosing the view its
# encoders see with a frame whose object touches the image border counted `--cut-input-weight` times a whole one
# (1 = the preset), and showing the encoders what lies outside the frame as `--model.crop-outside` says
# (`background`, the preset, or `checker`); then both calibrated and scored on val40 and on the 64 test objects
# (test64), side by side.
#   DATA=... [WORK=...] [CACHE=...] [RUNS="0:0 0:1"] [TEST64=1] benchmarks/cut_inputs.sh
# RUNS: two runs, each WEIGHT:SEED[:OUTSIDE] (the results' runs: "0:0 0:1", then "1:0:checker 1:1:checker").
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/cut_inputs}"
LIMIT="${LIMIT:-60}"  # a safety net: the runs end on their step count
STEPS="${STEPS:-13000}"
CACHE="${CACHE:-$W/cache}"
read -r -a runs <<< "${RUNS:-0:0 0:1}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
names=()
args=()
for spec in "${runs[@]}"; do
    IFS=: read -r weight seed outside <<< "$spec"
    outside="${outside:-background}"
    name="cut${weight}_s$seed"
    [ "$outside" = background ] || name="${outside}_$name"
    names+=("$name")
    args+=("$name" "$STEPS" --seed "$seed" --cut-input-weight "$weight" --model.crop-outside "$outside")
done
scored_pair "${args[@]:0:8}" -- "${args[@]:8:8}"
if [ "${TEST64:-1}" = 1 ]; then
    test64 "${names[0]}" "$W/${names[0]}" &
    test64 "${names[1]}" "$W/${names[1]}" &
    wait
fi
