#!/usr/bin/env bash
# One field for both passes as a further stage of the shipped weights (issue 12; --model.coarse-field shared,
# results/shared_field.md for the same comparison from scratch). Two further stages from
# src/affnerf/weights/affnerf-small.pt side by side, one core each, for the same MINUTES: "own" (the preset: the
# coarse field keeps placing the fine samples) and "shared" (--init-from takes the shipped fine field, which then
# places its own samples without gradients; the coarse field is dropped). Each has a fresh Adam, 2e-4 -> 2e-5 over
# a schedule about as long as it makes steps in that time (OWN_STEPS, SHARED_STEPS; the defaults are the step
# rates shared_field.md measured side by side on a 2-core VM without AVX-512, 209 and 251 steps a minute). Then
# each, on its own core: calibrated (32 validation objects), val40 (side_by_side.sh) and surface_errors.py (5 test
# objects a category). Result: results/fine_tune_shared_field.md (level: a further stage of converged weights gains
# nothing either way; the one field's gain is in steps a minute from scratch, results/shared_field.md).
#
#   DATA=/tmp/w/data WORK=/tmp/ft CACHE=/tmp/w/cache [MINUTES=50] benchmarks/fine_tune_shared_field.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
MINUTES="${MINUTES:-50}"
OWN_STEPS="${OWN_STEPS:-$((MINUTES * 209))}"
SHARED_STEPS="${SHARED_STEPS:-$((MINUTES * 251))}"
SHIPPED=src/affnerf/weights/affnerf-small.pt
export OMP_NUM_THREADS=1
mkdir -p "$W"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh

# stage NAME CORE STEPS KIND: the further stage W/NAME on core CORE (side_by_side.sh's calibrated_stage, stopped
# at MINUTES), then its scores (see above)
stage() {
    taskset -cp "$2" "$BASHPID" > /dev/null  # this subshell (start it with &) and all it starts
    calibrated_stage "$1" "$SHIPPED" "$3" "$CACHE" --time-limit "$MINUTES" --val-every 0 --model.coarse-field "$4"
    val40 "$1" "$W/$1"
    .venv/bin/python benchmarks/surface_errors.py --data "$DATA" --run "$W/$1" --methods affnerf \
        --out "$W/surface_errors_$1.json"
}

warm_cache "$CACHE"
stage own 0 "$OWN_STEPS" own > "$W/own.log" 2>&1 &
stage shared 1 "$SHARED_STEPS" shared > "$W/shared.log" 2>&1 &
wait
for name in own shared; do echo "== $name"; sed -n 5,9p "$W/val40_$name/table2.md"; done
