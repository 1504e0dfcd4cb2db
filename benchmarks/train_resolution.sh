#!/usr/bin/env bash
# Training resolution (issue 12, "thin parts count"): the `small` preset trains on quarter-resolution frames
# (100x75), where the affordance labels are nearest-resized, so a bucket's bail or a pair of eyeglasses' frame is
# kept or dropped pixel by pixel, while Table 2 scores at half resolution (200x150). A ray costs the same at any
# resolution; only the frame cache grows (x4). Two further stages from the shipped weights, side by side on one core
# each for the same MINUTES with the same schedule (a fresh Adam, 2e-4 -> 2e-5, as fine_tune_consistency.sh):
# "plain" on quarter-resolution frames, "half" on half-resolution frames (`--image-scale 0.5`), each with its own
# frame cache. Then each is calibrated (32 validation objects) and scored on val40 at 100x75 and at 200x150.
#
#   DATA=/tmp/w/data WORK=/tmp/tr benchmarks/train_resolution.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
MINUTES="${MINUTES:-35}"
STEPS="${STEPS:-19000}"  # the schedule's length: what one core makes in 35 minutes beside another run
LIMIT="$MINUTES"
export OMP_NUM_THREADS=1
SHIPPED=src/affnerf/weights/affnerf-small.pt
STAGE=(--init-from "$SHIPPED" --optim.lr 2e-4 --optim.lr-final 2e-5)
mkdir -p "$W"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh

if [ "${SKIP_TRAINING:-0}" != 1 ]; then
    W="$W/warm-a" warm_cache "$W/cache_quarter" --image-scale 0.25 &
    W="$W/warm-b" warm_cache "$W/cache_half" --image-scale 0.5 &
    wait
    timed_small_run plain "$STEPS" "${STAGE[@]}" --cache-dir "$W/cache_quarter" --image-scale 0.25 &
    timed_small_run half "$STEPS" "${STAGE[@]}" --cache-dir "$W/cache_half" --image-scale 0.5 &
    wait
    for name in plain half; do
        .venv/bin/affnerf eval calibrate --run "$W/$name" --data "$DATA" --max-objects 32 --device cpu \
            > "$W/calibrate_$name.log" 2>&1 &
    done
    wait
fi
for name in plain half; do
    val40 "$name" "$W/$name" > "$W/val40_$name.log" 2>&1 &
done
wait
for name in plain half; do
    VAL40_SCALE=0.5 val40 "${name}_200x150" "$W/$name" > "$W/val40_${name}_200x150.log" 2>&1 &
done
wait
for name in plain half; do
    echo "== $name"
    sed -n 5,9p "$W/val40_$name/table2.md"
    sed -n 5,9p "$W/val40_${name}_200x150/table2.md"
done
