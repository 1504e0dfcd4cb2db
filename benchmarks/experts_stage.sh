#!/usr/bin/env bash
# Weight experts as a further stage from the shipped weights (issue 12; benchmarks/results/experts.md): the shipped
# recipe's further stage (a fresh Adam, 2e-4 -> 2e-5) on the shipped model as it is, against the same stage with
# eight trunk weight sets per layer that start as copies of the shipped ones (`--model.experts 8`; the router is
# new), side by side, one core each, each with a schedule as long as the steps it takes in LIMIT minutes; then
# both calibrated and scored on val40.
#   DATA=... benchmarks/experts_stage.sh      (LIMIT minutes; STEPS_PLAIN, STEPS_EXPERTS: the schedules' lengths)
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/experts_stage}"
LIMIT="${LIMIT:-40}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
SHIPPED=src/affnerf/weights/affnerf-small.pt
STAGE=(--model.coarse-field own --optim.schedule exponential --optim.warmup-steps 0 --time-limit "$LIMIT")
warm_cache "$CACHE" --model.coarse-field own
calibrated_stage plain_stage "$SHIPPED" "${STEPS_PLAIN:-12000}" "$CACHE" "${STAGE[@]}" &
calibrated_stage experts_stage "$SHIPPED" "${STEPS_EXPERTS:-10700}" "$CACHE" "${STAGE[@]}" --model.experts 8 &
wait
rm -rf "$W/val40_plain_stage" "$W/val40_experts_stage"
val40 plain_stage "$W/plain_stage" &
val40 experts_stage "$W/experts_stage" &
wait
