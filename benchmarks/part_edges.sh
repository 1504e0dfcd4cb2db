#!/usr/bin/env bash
# Rays near the edges between parts (issue 12; results/part_edges.md): two `small` runs from scratch, side by side,
# one core each, the same 13,000-step schedule as shape_pooling.sh (whose `keypoints` runs were the preset as it is
# now, and are reproduced exactly here), each with a share of its object rays drawn near the edges between parts
# inside the object (`--edge-fraction`, 0 = the preset) in a band of `--edge-radius` pixels; then both calibrated
# and scored on val40 and on the 64 test objects (test64), side by side.
#   DATA=... [WORK=...] [CACHE=...] [RUNS="0:1:0 0.2:1:0"] [TEST64=1] benchmarks/part_edges.sh
# RUNS: two runs, each FRACTION:RADIUS:SEED[:FOREGROUND] (the results' runs: "0:1:0 0.2:1:0", then "0.1:1:0
# 0.2:1:1", then "0.1:1:0:0.6 0.1:1:1:0.6" with TEST64=0: a foreground share of 0.6 of which 0.1 near the edges
# leaves the object's uniform share at the preset's 0.5 and takes the edges' rays from the uniform ones instead).
set -euo pipefail
cd "$(dirname "$0")/.."
read -r -a runs <<< "${RUNS:-0:1:0 0.2:1:0}"
options=()
for spec in "${runs[@]}"; do
    IFS=: read -r fraction radius seed foreground <<< "$spec"
    foreground="${foreground:-0.5}"
    name="edges${fraction}r${radius}_s$seed"
    [ "$fraction" = 0 ] && name="preset_s$seed"
    [ "$foreground" = 0.5 ] || name="${name}_fg$foreground"
    options+=("$name --seed $seed --edge-fraction $fraction --edge-radius $radius --foreground-fraction $foreground")
done
A="${options[0]}" B="${options[1]}" WORK="${WORK:-benchmarks/.work/part_edges}" exec benchmarks/scratch_pair.sh
