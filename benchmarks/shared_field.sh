#!/usr/bin/env bash
# One field for both passes (issue 12, quality per CPU-minute; --model.coarse-field shared): the small preset's
# coarse field costs a forward and backward pass of its own at the stratified samples and half of the 3D
# supervision, and serves only to place the fine samples (predict, meshes and the fast renderer use the fine
# field). With `shared` the fine field places its own samples, evaluated there without gradients (NeuS's
# hierarchical sampling). Two `small` runs from scratch side by side (one core each) for the same MINUTES, each
# with a schedule about as long as it makes steps in that time (OWN_STEPS, SHARED_STEPS: measure them with a short
# pilot first, `STEPS_PILOT=300 benchmarks/shared_field.sh`): "own" (the preset) and "shared". Then both are
# calibrated (32 validation objects) and scored on val40 (side_by_side.sh) and by surface_errors.py.
#
#   DATA=/tmp/w/data WORK=/tmp/shared CACHE=... OWN_STEPS=N SHARED_STEPS=M benchmarks/shared_field.sh
#
# EXTRA: more training options for both runs (e.g. "--seed 1"); SURFACE_ERRORS=0 skips surface_errors.py.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
MINUTES="${MINUTES:-45}"
LIMIT="$MINUTES"
read -r -a EXTRA_ARGS <<< "${EXTRA:-}"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores
mkdir -p "$W"

# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$CACHE"
if [[ -n "${STEPS_PILOT:-}" ]]; then  # seconds a step of each, side by side
    for kind in own shared; do
        timed_small_run "pilot_$kind" "$STEPS_PILOT" --cache-dir "$CACHE" --model.coarse-field "$kind" &
    done
    wait
    for kind in own shared; do grep -h '"seconds"' "$W/pilot_$kind/summary.json" || true; done
    exit 0
fi
timed_small_run own "${OWN_STEPS:?}" --cache-dir "$CACHE" --model.coarse-field own "${EXTRA_ARGS[@]}" &
timed_small_run shared "${SHARED_STEPS:?}" --cache-dir "$CACHE" --model.coarse-field shared "${EXTRA_ARGS[@]}" &
wait
for name in own shared; do
    (calibrated_val40 "$name" "$W/$name" &&
        { [[ "${SURFACE_ERRORS:-1}" == 0 ]] || .venv/bin/python benchmarks/surface_errors.py --data "$DATA" --run "$W/$name" \
            --out "$W/surface_errors_$name.json"; }) > "$W/score_$name.log" 2>&1 &
done
wait
for name in own shared; do echo "== $name"; sed -n 5,9p "$W/val40_$name/table2.md"; done
