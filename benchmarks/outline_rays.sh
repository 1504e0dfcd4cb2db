#!/usr/bin/env bash
# Rays near the object's outline (issue 12; benchmarks/results/outline_rays.md): the `small` preset as it was (half
# its rays on the object's pixels, the rest uniform over the image, where about 95 % land on background far from the
# object; `--outline-fraction 0`) against the same preset with SHARE of the rays taken from the uniform ones and
# drawn near the object (an object pixel moved by up to RADIUS pixels of the 100 x 75 training images along each
# axis), from scratch, side by side, one core each, the same schedule and minutes; then both calibrated and scored
# on val40. The preset draws 0.4 so since these runs.
#   DATA=... benchmarks/outline_rays.sh      (SHARE 0.4; RADIUS 3; SEED 0, the training seed of both runs; LIMIT
#   minutes; STEPS: the schedule's length)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/outline_rays}"
LIMIT="${LIMIT:-40}"
STEPS="${STEPS:-15000}"
SHARE="${SHARE:-0.4}"
RADIUS="${RADIUS:-3}"
SEED="${SEED:-0}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
tag=$(seed_tag)
scored_pair "half$tag" "$STEPS" --seed "$SEED" --outline-fraction 0 -- "outline$SHARE$tag" "$STEPS" --seed "$SEED" \
    --outline-fraction "$SHARE" --outline-radius "$RADIUS"
