#!/usr/bin/env bash
# Is the small preset short of capacity? (benchmarks/results/capacity.md, issue 12). The shipped model plateaus
# (second_stage.md: a third stage at 100x75 or 200x150 adds nothing) while it still fits its own training objects
# poorly, and test-time fits from training objects' codes are no sharper (test_time_variants.md): the decoder looks
# like the limit. Side by side, one core each, the same minutes: the small preset against a field twice as wide
# (128, colour and affordance heads 64), each with a schedule that ends when the minutes do (SMALL_STEPS and
# WIDE_STEPS: measured here side by side, 9.4 and 4.3 steps a second); every checkpoint scored on the ladder's
# 16 validation objects.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/capacity}"
MINUTES="${MINUTES:-35}"
export OMP_NUM_THREADS=1
SMALL_STEPS="${SMALL_STEPS:-19000}"
WIDE_STEPS="${WIDE_STEPS:-9000}"
LIMIT="$((MINUTES + 1))"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
# build the frame and point cache before either run is timed
warm_cache "$W/cache"
timed_small_run small "$SMALL_STEPS" --cache-dir "$W/cache" &
timed_small_run wide "$WIDE_STEPS" --cache-dir "$W/cache" --model.field-width 128 --model.color-width 64 \
    --model.affordance-width 64 &
wait
score_runs small wide
