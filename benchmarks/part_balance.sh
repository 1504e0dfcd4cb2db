#!/usr/bin/env bash
# Part-balanced 3D supervision points (issues 12 and 13; benchmarks/results/part_balance.md): do a bail, a handle or
# a temple learn their shape when their surface gets its share of the near-surface points instead of its area's?
# For each balance b in BALANCES (0 = the shipped sampling), a further stage from the shipped weights (a fresh Adam,
# 2e-4 -> 2e-5 over 15,500 steps, stopped at 14,393: fine_tune_jitter.sh's plain stage, which ran out of its 30
# minutes there), single-threaded, two at a time, each pinned to its own core with a cache of its own (point sets of
# another balance would be remade in place); then each calibrated, scored on val40 and by surface_errors.py, and grasped
# on the validation objects of GRASP_CATEGORIES (side_by_side.sh's scored_stage).
#   DATA=... benchmarks/part_balance.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/part_balance}"
BALANCES="${BALANCES:-0 0.5 1.0}"
export GRASP_CATEGORIES="${GRASP_CATEGORIES:-bucket,cabinet,teapot,eyeglasses}"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh

i=0
for b in $BALANCES; do
    scored_stage "balance$b" $((i % 2)) "$W/cache$b" --point-part-balance "$b" &
    i=$((i + 1))
    [ $((i % 2)) = 0 ] && wait
done
wait
