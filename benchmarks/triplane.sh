#!/usr/bin/env bash
# Does a triplane decoder of the shape code learn faster than the paper's concatenated code? (issue 12;
# benchmarks/results/triplane.md). The code oracle (code_oracle.md) found the decoder, not the single image, capping
# the model; a wider field (wide_full_budget.md) and FiLM (fine_tune_film.md) did not lift it. Here the code is also
# decoded once per object into three feature planes (--model.conditioning triplane, affnerf.model.triplane) that
# the same small field reads at each point beside the code. Three runs, one core each and always one other training
# on the other core: the small preset beside planes of 64 texels; then planes of 32 texels beside the first two's
# evaluation. Each schedule ends by its step count (SMALL_STEPS, TRI64_STEPS, TRI32_STEPS: 33, 29 and 29 minutes
# there) or MINUTES, whichever is first; each final model is evaluated on 40 validation objects (5 per category,
# 5 target views at 100x75, meshes at 96^3), and the small run also at TRI64_STEPS' neighbourhood (step 11,000).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/triplane}"
MINUTES="${MINUTES:-40}"
export OMP_NUM_THREADS=1
SMALL_STEPS="${SMALL_STEPS:-18000}"
TRI64_STEPS="${TRI64_STEPS:-10500}"
TRI32_STEPS="${TRI32_STEPS:-11500}"
LIMIT="$MINUTES"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
CACHE="${CACHE:-$W/cache}"
warm_cache "$CACHE"
timed_small_run small "$SMALL_STEPS" --cache-dir "$CACHE" &
timed_small_run tri64 "$TRI64_STEPS" --cache-dir "$CACHE" --model.conditioning triplane &
wait
timed_small_run tri32 "$TRI32_STEPS" --cache-dir "$CACHE" --model.conditioning triplane --model.plane-resolution 32 &
val40 small "$W/small"
val40 tri64 "$W/tri64"
val40 small11k "$W/small/checkpoints/step_00011000.pt"
wait
val40 tri32 "$W/tri32"
