#!/usr/bin/env bash
# Two further stages from the same weights (default: the shipped ones), side by side, one core each, each with its
# own training options, the same schedule (a fresh Adam, 2e-4 -> 2e-5 over STEPS) and the same time limit; then each
# calibrated (32 validation objects) and scored on val40 and the 64 test objects (side_by_side.sh), and the scores
# gathered by collect_stages.py with the shipped weights' rows as the reference (see results/lovasz_stage.md):
#   DATA=... [WORK=...] [CACHE=...] [INIT=...] [STEPS=9000] [LIMIT=30] \
#       A="NAME [TRAIN OPTIONS...]" B="NAME [TRAIN OPTIONS...]" benchmarks/stage_pair.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/stage_pair}"
LIMIT="${LIMIT:-30}"  # a safety net: the stages end on their step count
STEPS="${STEPS:-9000}"
CACHE="${CACHE:-$W/cache}"
INIT="${INIT:-src/affnerf/weights/affnerf-small.pt}"
read -r -a first <<< "${A:?A=\"NAME [TRAIN OPTIONS...]\"}"
read -r -a second <<< "${B:?B=\"NAME [TRAIN OPTIONS...]\"}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$CACHE"
scored_further_stage "${first[0]}" "$INIT" "$STEPS" "$CACHE" --time-limit "$LIMIT" "${first[@]:1}" &
scored_further_stage "${second[0]}" "$INIT" "$STEPS" "$CACHE" --time-limit "$LIMIT" "${second[@]:1}" &
wait
.venv/bin/python benchmarks/collect_stages.py --work "$W" --names "${first[0]}" "${second[0]}" --compact \
    --reference benchmarks/results/retrain_keypoints.json:run:shipped --out "$W/stage_pair.json"
