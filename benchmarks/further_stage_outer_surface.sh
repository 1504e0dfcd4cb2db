#!/usr/bin/env bash
# The shipped recipe's further stage (results/sdf_recipe.md, `stage2`) given to the first stage trained from scratch
# on version-4 (outer-surface) point sets (results/retrain_outer_surface.md, committed as
# benchmarks/candidates/affnerf-small-sdf-v4.pt in commit 29fc4da), then calibrated and scored by val40 beside the
# weights shipped until then, that recipe on version-3 point sets (src/affnerf/weights/affnerf-small.pt in commit
# ab24f38; issue 12; results/further_stage_outer_surface.md). The result ships since.
# Both files are read from those commits unless FIRST and BEFORE name them.
#   DATA=... [WORK=...] [CACHE=...] benchmarks/further_stage_outer_surface.sh
# One core for each training (a fresh Adam, 2e-4 -> 2e-5 over 19,000 steps), as the shipped stage had, beside the
# same stage with 96-pixel encoder crops on the other core; the scorings run two at a time, one core each.
# SKIP_TRAINING=1 only evaluates.
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/further_stage_outer_surface}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"
FIRST="${FIRST:-$W/first_stage_v4.pt}"
BEFORE="${BEFORE:-$W/shipped_v3.pt}"
[ -f "$FIRST" ] || git show 29fc4da:benchmarks/candidates/affnerf-small-sdf-v4.pt > "$FIRST"
[ -f "$BEFORE" ] || git show ab24f38:src/affnerf/weights/affnerf-small.pt > "$BEFORE"

if [ "${SKIP_TRAINING:-0}" != 1 ]; then
    # beside it, the same stage with 96-pixel encoder crops (a step costs about 5 % more, so 18,100 steps), on a
    # cache of its own (the crops are cached at their side)
    warm_cache "$W/cache96" --model.encoder-resolution 96
    calibrated_stage v4_stage2 "$FIRST" 19000 "$CACHE" &
    calibrated_stage v4_stage2_96 "$FIRST" 18100 "$W/cache96" --model.encoder-resolution 96 &
    wait
fi
rm -rf "$W/val40_shipped" "$W/val40_v4_stage2" "$W/val40_v4_stage2_96"
val40 shipped "$BEFORE" &
val40 v4_stage2 "$W/v4_stage2" &
wait
val40 v4_stage2_96 "$W/v4_stage2_96"
