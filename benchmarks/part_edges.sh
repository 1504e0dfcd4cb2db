#!/usr/bin/env bash
# Rays near the edges between parts (issue 12; results/part_edges.md): the `small` preset from scratch against the
# same preset with a share of its object rays drawn near the edges between parts inside the object
# (`--edge-fraction`, `--edge-radius`), side by side, one core each, the same schedule and training seed; then both
# calibrated and scored on val40 and on the 64 test objects (test64), side by side. 13,000 steps as
# shape_pooling.sh, whose `keypoints` runs were the preset as it is now.
#   DATA=... [WORK=...] [CACHE=...] [SEED=0] [EDGE=0.2] [RADIUS=1] benchmarks/part_edges.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/part_edges}"
LIMIT="${LIMIT:-60}"  # a safety net: the runs end on their step count
STEPS="${STEPS:-13000}"
SEED="${SEED:-0}"
EDGE="${EDGE:-0.2}"
RADIUS="${RADIUS:-1}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
tag=$(seed_tag)
edges="edges${EDGE}r$RADIUS$tag"
scored_pair "preset$tag" "$STEPS" --seed "$SEED" -- "$edges" "$STEPS" --seed "$SEED" \
    --edge-fraction "$EDGE" --edge-radius "$RADIUS"
test64 "preset$tag" "$W/preset$tag" &
test64 "$edges" "$W/$edges" &
wait
