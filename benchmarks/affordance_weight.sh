#!/usr/bin/env bash
# The weight λ of the rendered rays' affordance cross-entropy (issue 12: "a λ chosen by measurement"; the `small`
# preset has Semantic-NeRF's 4e-2, never swept on the current recipe): one `small` run from scratch per value of
# LAMBDAS, side by side (one core each) for the same MINUTES with the same STEPS-long schedule, then each calibrated
# (32 validation objects) and scored on val40 (side_by_side.sh), side by side.
#
#   DATA=/tmp/w/data WORK=/tmp/lambda CACHE=... MINUTES=30 STEPS=7600 LAMBDAS="0.04 0.15" benchmarks/affordance_weight.sh
#
# EXTRA: more training options for every run (e.g. "--seed 2").
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
MINUTES="${MINUTES:-30}"
LIMIT="$MINUTES"
LAMBDAS="${LAMBDAS:-0.04 0.15}"
read -r -a EXTRA_ARGS <<< "${EXTRA:-}"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores
mkdir -p "$W"

# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$CACHE"
for value in $LAMBDAS; do
    timed_small_run "lambda$value" "${STEPS:?STEPS: the schedule, about the steps MINUTES allow}" \
        --cache-dir "$CACHE" --affordance-weight "$value" "${EXTRA_ARGS[@]}" &
done
wait
for value in $LAMBDAS; do
    calibrated_val40 "lambda$value" "$W/lambda$value" > "$W/score_lambda$value.log" 2>&1 &
done
wait
for value in $LAMBDAS; do echo "== λ $value"; sed -n 5,9p "$W/val40_lambda$value/table2.md"; done
