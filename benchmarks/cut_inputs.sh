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
read -r -a runs <<< "${RUNS:-0:0 0:1}"
options=()
for spec in "${runs[@]}"; do
    IFS=: read -r weight seed outside <<< "$spec"
    outside="${outside:-background}"
    name="cut${weight}_s$seed"
    [ "$outside" = background ] || name="${outside}_$name"
    options+=("$name --seed $seed --cut-input-weight $weight --model.crop-outside $outside")
done
A="${options[0]}" B="${options[1]}" WORK="${WORK:-benchmarks/.work/cut_inputs}" exec benchmarks/scratch_pair.sh
