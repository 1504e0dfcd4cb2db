#!/usr/bin/env bash
# Training precision, --precision fp32 against bf16 (autocast to bfloat16; benchmarks/results/precision.md).
# PARTS (default "speed quality"):
# - speed: the two precisions side by side, one core each: the `small` preset for 400 steps of the plain further
#   stage from the shipped weights (the rays a second of the whole step, from metrics.jsonl), and the `paper` preset
#   from scratch on the bottles for PAPER_STEPS steps (its own frame cache each; rays a second logged every 10 steps),
#   and the `small` preset with the field twice as wide (capacity.md) from scratch for 300 steps, one after the other.
# - quality: the plain further stage (side_by_side.sh's scored_stage: 14,393 steps from the shipped weights,
#   calibrated, val40, surface errors, grasps) in bf16, to set beside the fp32 one (fine_tune_jitter.sh's `plain`,
#   same seed, same schedule; points_schedule.md's `plain_seed1` gives the seed's share).
#   DATA=... benchmarks/precision.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/precision}"
CACHE="${CACHE:-$W/cache}"
PAPER_STEPS="${PAPER_STEPS:-20}"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"

speed_run() {  # speed_run CORE NAME PRECISION TRAIN OPTIONS...
    local core=$1 name=$2 precision=$3
    shift 3
    rm -rf "${W:?}/$name"
    taskset -c "$core" env OMP_NUM_THREADS=1 .venv/bin/affnerf train --data "$DATA" --out "$W/$name" --device cpu \
        --checkpoint-every 100000 --val-every 0 --no-progress --precision "$precision" "$@" > "$W/$name.log" 2>&1
}

for part in ${PARTS:-speed quality}; do
    case $part in
    speed)
        warm_cache "$CACHE" --points-weight 0.1
        for p in fp32 bf16; do
            speed_run $([ $p = fp32 ] && echo 0 || echo 1) "small_$p" $p --config small --steps 15500 --stop-at 400 \
                --log-every 50 --init-from src/affnerf/weights/affnerf-small.pt --optim.lr 2e-4 \
                --optim.lr-final 2e-5 --cache-dir "$CACHE" &
        done
        wait
        for p in fp32 bf16; do
            speed_run $([ $p = fp32 ] && echo 0 || echo 1) "paper_$p" $p --config paper --steps 1000 \
                --stop-at "$PAPER_STEPS" --log-every 10 --categories bottle --cache-dir "$W/cache_paper_$p" &
        done
        wait
        for p in fp32 bf16; do  # one after the other on core 1 (in the committed run, beside a training on core 0)
            speed_run 1 "wide_$p" $p --config small --steps 46000 --stop-at 300 --log-every 50 --cache-dir "$CACHE" \
                --model.field-width 128 --model.color-width 64 --model.affordance-width 64
        done
        ;;
    quality)
        scored_stage bf16 0 "$CACHE" --precision bf16 > "$W/bf16.log" 2>&1
        ;;
    esac
done
