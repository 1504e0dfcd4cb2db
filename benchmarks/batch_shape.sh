#!/usr/bin/env bash
# How should a step's supervision be spread over objects? (issue 12; benchmarks/results/batch_shape.md). The small
# preset draws 4 objects a step, 64 rays and 1,024 3D points each. The code oracle (code_oracle.md) left "more
# supervision per object visit" untested: here the same rays and points a step (the field's cost) over 2, 8 and 16
# objects (128, 32 and 16 rays each), and 8 objects with the preset's 1,024 points each. Two side by side, one core
# each, 33.5 minutes or 17,500 steps; the preset's own run is triplane.sh's `small` (18,000 steps in 33.5 minutes
# beside another training). Each final model is evaluated on 40 validation objects.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/batch_shape}"
LIMIT="${MINUTES:-33.5}"
STEPS="${STEPS:-17500}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
CACHE="${CACHE:-$W/cache}"
warm_cache "$CACHE"
timed_small_run o8 "$STEPS" --cache-dir "$CACHE" --objects-per-step 8 --points-per-object 512 &
timed_small_run o2 "$STEPS" --cache-dir "$CACHE" --objects-per-step 2 --points-per-object 2048 &
wait
timed_small_run o16 "$STEPS" --cache-dir "$CACHE" --objects-per-step 16 --points-per-object 256 &
timed_small_run o8p "$STEPS" --cache-dir "$CACHE" --objects-per-step 8 --points-per-object 1024 &
wait
for name in o2 o8 o16 o8p; do
    val40 "$name" "$W/$name" &
done
wait
# the shorter pair: 16 against 32 objects a step, 18 minutes each
LIMIT=18
timed_small_run s16 9000 --cache-dir "$CACHE" --objects-per-step 16 --points-per-object 256 &
timed_small_run s32 8000 --cache-dir "$CACHE" --objects-per-step 32 --points-per-object 128 &
wait
for name in s16 s32; do
    val40 "$name" "$W/$name" &
done
wait
