#!/usr/bin/env bash
# Share of a step's rays drawn on the object (issue 12; benchmarks/results/foreground_fraction.md): the `small`
# preset as it ships (half its rays on the object's pixels, the rest uniform over the image) against the same
# preset with FRACTION of them on the object, from scratch, side by side, one core each, the same schedule and
# minutes (the cost of a step does not depend on where its rays fall); then both calibrated and scored on val40.
#   DATA=... benchmarks/foreground_fraction.sh      (FRACTION 0.8; LIMIT minutes; STEPS: the schedule's length)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/foreground_fraction}"
LIMIT="${LIMIT:-40}"
STEPS="${STEPS:-15000}"
FRACTION="${FRACTION:-0.8}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
# --outline-fraction 0: the preset's rule when these ran (its 40 % near the outline came after, outline_rays.sh)
scored_pair half "$STEPS" --outline-fraction 0 -- "fg$FRACTION" "$STEPS" --foreground-fraction "$FRACTION" \
    --outline-fraction 0
