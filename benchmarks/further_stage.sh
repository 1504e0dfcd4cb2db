#!/usr/bin/env bash
# A further training stage from the shipped weights, with and without one change, side by side (issue 12):
#   benchmarks/further_stage.sh NAME STEPS [TRAIN OPTIONS...]
# trains W/plain (the shipped loss and model, PLAIN_STEPS) and W/NAME (the same with TRAIN OPTIONS, STEPS) from
# src/affnerf/weights/affnerf-small.pt, one core each, for the same MINUTES, each with a fresh Adam and a schedule
# 2e-4 -> 2e-5 that ends when the minutes do (as the third stage of results/second_stage.md; pass the steps each
# run makes in MINUTES side by side); then scores every checkpoint of both, and the shipped model, on the ladder's 16
# validation objects (SCORE=0 skips the scoring). Used by the fine_tune_*.sh scripts.
set -euo pipefail
cd "$(dirname "$0")/.."
NAME="$1"
STEPS="$2"
shift 2
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
MINUTES="${MINUTES:-26}"
PLAIN_STEPS="${PLAIN_STEPS:-8500}"
export OMP_NUM_THREADS=1
SHIPPED=src/affnerf/weights/affnerf-small.pt
STAGE=(--init-from "$SHIPPED" --optim.lr 2e-4 --optim.lr-final 2e-5 --cache-dir "$W/cache")
LIMIT="$MINUTES"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
# build the frame and point cache before either run is timed
warm_cache "$W/cache"
timed_small_run plain "$PLAIN_STEPS" "${STAGE[@]}" &
timed_small_run "$NAME" "$STEPS" "${STAGE[@]}" "$@" &
wait
[ "${SCORE:-1}" = 1 ] || exit 0  # SCORE=0: the caller scores the runs its own way
score_runs plain "$NAME"
.venv/bin/python benchmarks/ablation_ladder.py --data "$DATA" --work "$W" --out "$W/score_shipped.json" \
    --reference "$SHIPPED"
