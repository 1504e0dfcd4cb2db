#!/usr/bin/env bash
# The learning-rate schedule of the `small` preset (issue 12; the preset falls exponentially 1e-3 -> 2e-5, never
# swept): a cosine fall after a linear warm-up (`--optim.schedule cosine --optim.warmup-steps`), at the preset's
# peak and at twice it, from scratch side by side (one core each) for the same STEPS (a step costs the same under
# any schedule), then each calibrated (32 validation objects) and scored on val40 (side_by_side.sh), side by side.
# The preset's own run at the same STEPS and seed is affordance_weight.sh's λ 0.04 run (training is deterministic
# on one thread: its logged losses are reproduced to the last digit).
#
#   DATA=/tmp/w/data WORK=/tmp/schedule CACHE=... MINUTES=60 STEPS=9000 benchmarks/learning_rate_schedule.sh
#
# WARMUP: warm-up steps (300); PEAKS: the peak rates, one run each ("1e-3 2e-3"); EXTRA: more training options.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
MINUTES="${MINUTES:-60}"
LIMIT="$MINUTES"
PEAKS="${PEAKS:-1e-3 2e-3}"
read -r -a EXTRA_ARGS <<< "${EXTRA:-}"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores
mkdir -p "$W"

# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$CACHE"
for peak in $PEAKS; do
    timed_small_run "cosine$peak" "${STEPS:?STEPS: the schedule}" --cache-dir "$CACHE" --optim.schedule cosine \
        --optim.warmup-steps "${WARMUP:-300}" --optim.lr "$peak" "${EXTRA_ARGS[@]}" &
done
wait
for peak in $PEAKS; do
    calibrated_val40 "cosine$peak" "$W/cosine$peak" > "$W/score_cosine$peak.log" 2>&1 &
done
wait
for peak in $PEAKS; do echo "== cosine, peak $peak"; sed -n 5,9p "$W/val40_cosine$peak/table2.md"; done
