#!/usr/bin/env bash
# Keypoints grown into the shipped weights (issue 12; benchmarks/results/shape_pooling.md, "As a further stage"):
# a further stage of the shipped weights whose shape encoder is grown into `--model.shape-pooling keypoints` (the
# keypoints enter the code with zero weights, so it starts as the shipped model) against the same stage that keeps
# the mean, side by side, one core each, the same schedule (a fresh Adam, 2e-4 -> 2e-5 over STEPS) and minutes;
# then each calibrated on 32 validation objects and scored on val40 and the 64 test objects.
#   DATA=... benchmarks/keypoint_stage.sh      (STEPS: the schedule's length; LIMIT minutes); the scores in
#   W/keypoint_stage.json (results/keypoint_stage.json)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/keypoint_stage}"
LIMIT="${LIMIT:-25}"
STEPS="${STEPS:-6000}"
CACHE="${CACHE:-$W/cache}"
SHIPPED=src/affnerf/weights/affnerf-small.pt
# the shipped weights' own recipe: two fields, the exponential fall (MODEL_CARD.md)
OWN="--model.coarse-field own --optim.schedule exponential --optim.warmup-steps 0 --time-limit $LIMIT"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$CACHE"
# shellcheck disable=SC2086
scored_further_stage stage_mean "$SHIPPED" "$STEPS" "$CACHE" $OWN --model.shape-pooling mean &
# shellcheck disable=SC2086
scored_further_stage stage_keypoints "$SHIPPED" "$STEPS" "$CACHE" $OWN --model.shape-pooling keypoints &
wait
.venv/bin/python benchmarks/collect_stages.py --work "$W" --names stage_mean stage_keypoints --compact \
    --out "$W/keypoint_stage.json"
