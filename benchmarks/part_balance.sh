#!/usr/bin/env bash
# Part-balanced 3D supervision points (issues 12 and 13; benchmarks/results/part_balance.md): do a bail, a handle or
# a temple learn their shape when their surface gets its share of the near-surface points instead of its area's?
# For each balance b in BALANCES (0 = the shipped sampling), a further stage from the shipped weights (a fresh Adam,
# 2e-4 -> 2e-5 over 15,500 steps, stopped at 14,393: fine_tune_jitter.sh's plain stage, which ran out of its 30
# minutes there), single-threaded, two at a time, each pinned to its own core with a cache of its own (point sets of
# another balance would be remade in place); then each calibrated (eval calibrate, 32 validation objects), scored on val40
# (side_by_side.sh) and grasped on the validation objects of GRASP_CATEGORIES (eval grasp, 5 each).
#   DATA=... benchmarks/part_balance.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/part_balance}"
BALANCES="${BALANCES:-0 0.5 1.0}"
GRASP_CATEGORIES="${GRASP_CATEGORIES:-bucket,cabinet,teapot,eyeglasses}"
export OMP_NUM_THREADS=1
SHIPPED=src/affnerf/weights/affnerf-small.pt
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh

# one_balance B CORE: the stage with balance B, its calibration, val40 and grasps, all pinned to core CORE
one_balance() {
    local b=$1 run="$W/balance$1"
    taskset -cp "$2" "$BASHPID" > /dev/null  # this subshell and everything it starts
    .venv/bin/affnerf train --data "$DATA" --out "$run" --config small --steps 15500 --stop-at 14393 \
        --device cpu --checkpoint-every 1000 --keep-checkpoints 100 --val-every 0 --no-progress \
        --init-from "$SHIPPED" --optim.lr 2e-4 --optim.lr-final 2e-5 --cache-dir "$W/cache$b" --point-part-balance "$b"
    .venv/bin/affnerf eval calibrate --run "$run" --data "$DATA" --max-objects 32 --device cpu
    val40 "balance$b" "$run"
    .venv/bin/affnerf eval grasp --run "$run" --data "$DATA" --split val --max-objects 5 \
        --categories "$GRASP_CATEGORIES" --no-pictures --device cpu --out "$W/grasp_balance$b"
}

i=0
for b in $BALANCES; do
    one_balance "$b" $((i % 2)) &
    i=$((i + 1))
    [ $((i % 2)) = 0 ] && wait
done
wait
