#!/usr/bin/env bash
# Time to quality with the shipped recipe (issue 12; benchmarks/results/time_to_quality_current.md): the `small`
# preset as it ships (its own schedule, planned for STEPS) from scratch on ONE core, stopped when MINUTES are up
# (22, a third of the 66 minutes of one core the model shipped when the issue was filed trained for), then every
# checkpoint and that original model scored by time_to_quality.py on its 16 validation objects that neither saw.
# The frame and point cache is built before the clock starts.
#   DATA=... ORIGINAL=original.pt benchmarks/time_to_quality.sh
# ORIGINAL: `git show 17260ac:src/affnerf/weights/affnerf-small.pt > original.pt` (2026-11-23 morning).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
ORIGINAL="${ORIGINAL:?the model shipped when issue 12 was filed}"
W="${WORK:-benchmarks/.work/time_to_quality}"
LIMIT="${MINUTES:-22}"
STEPS="${STEPS:-11500}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$W/cache"
timed_small_run current "$STEPS" --cache-dir "$W/cache"
.venv/bin/python benchmarks/time_to_quality.py --data "$DATA" --original "$ORIGINAL" --runs "$W/current" \
    --out "$W/time_to_quality_current.json"
