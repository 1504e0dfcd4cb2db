#!/usr/bin/env bash
# Keypoints in the shape code (issue 12; benchmarks/results/shape_pooling.md): the `small` preset (its shape
# encoder averages the last stage's features over the crop) against the same preset whose shape encoder also gives
# the code where each channel of its second and third stages peaks (`--model.shape-pooling keypoints`, a spatial
# soft-argmax), from scratch, side by side, one core each, the same schedule and minutes; then both calibrated and
# scored on val40 and on the 64 test objects (test64), side by side.
#   DATA=... benchmarks/shape_pooling.sh      (SEED 0, the training seed of both runs; LIMIT minutes; STEPS: the
#   schedule's length). Then, with both seeds scored: .venv/bin/python benchmarks/collect_stages.py --work W --names
#   mean keypoints mean_s1 keypoints_s1 --compact --out benchmarks/results/shape_pooling.json
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/shape_pooling}"
LIMIT="${LIMIT:-40}"
STEPS="${STEPS:-15000}"
SEED="${SEED:-0}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
tag=$(seed_tag)
scored_pair "mean$tag" "$STEPS" --seed "$SEED" -- "keypoints$tag" "$STEPS" --seed "$SEED" \
    --model.shape-pooling keypoints
test64 "mean$tag" "$W/mean$tag" &
test64 "keypoints$tag" "$W/keypoints$tag" &
wait
