#!/usr/bin/env bash
# More training objects (issue 12, "more and harder data"): is the encoder short of objects? code_oracle.md found
# the one-view codes 0.065 mIoU below fitted codes on new objects against 0.03 on training ones. Two runs side by
# side (one core each) for the same MINUTES with the same schedule: "plain" on DATA's 512 training objects, "more"
# on those plus EXTRA new objects of each category (extend_dataset.sh: the larger dataset BIG links DATA's objects
# and adds new ones to the training split; the validation and test objects stay DATA's). Then both are calibrated
# (32 validation objects) and scored on val40 (side_by_side.sh).
#   FROM=shipped (default): a further stage of the shipped weights (a fresh Adam, 2e-4 -> 2e-5, as
#                           further_stage.sh; results/more_objects.md)
#   FROM=scratch:           from the first step with the preset's schedule (1e-3 -> 2e-5;
#                           results/more_objects_scratch.md)
#
#   DATA=/tmp/w/data WORK=/tmp/mo [FROM=scratch] benchmarks/more_objects.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
BIG="${BIG:-$W/big}"
EXTRA="${EXTRA:-120}"
FROM="${FROM:-shipped}"
case "$FROM" in
    shipped) INIT=(--init-from src/affnerf/weights/affnerf-small.pt --optim.lr 2e-4 --optim.lr-final 2e-5)
             MINUTES="${MINUTES:-40}" STEPS="${STEPS:-14000}" ;;
    scratch) INIT=() MINUTES="${MINUTES:-45}" STEPS="${STEPS:-18000}" ;;
    *) echo "more_objects.sh: FROM must be shipped or scratch, not '$FROM'" >&2; exit 2 ;;
esac
# STEPS: the schedule's length, about what one core makes in MINUTES beside another run
LIMIT="$MINUTES"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores (more threads oversubscribe them)
mkdir -p "$W"
[ -f "$BIG/dataset.json" ] || benchmarks/extend_dataset.sh "$DATA" "$BIG" "$EXTRA" > "$W/generate.log" 2>&1

# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
# frames and point sets of both datasets (BIG holds DATA's objects), half the categories on each core
W="$W/warm-a" DATA="$BIG" warm_cache "$W/cache" --categories bottle,bucket,cabinet,eyeglasses &
W="$W/warm-b" DATA="$BIG" warm_cache "$W/cache" --categories pen,scissors,screwdriver,teapot &
wait
timed_small_run plain "$STEPS" "${INIT[@]}" --cache-dir "$W/cache" &
DATA="$BIG" timed_small_run more "$STEPS" "${INIT[@]}" --cache-dir "$W/cache" &
wait
for name in plain more; do
    (.venv/bin/affnerf eval calibrate --run "$W/$name" --data "$DATA" --max-objects 32 --device cpu &&
        val40 "$name" "$W/$name") > "$W/score_$name.log" 2>&1 &
done
wait
for name in plain more; do echo "== $name"; sed -n 5,9p "$W/val40_$name/table2.md"; done
