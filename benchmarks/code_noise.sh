#!/usr/bin/env bash
# Noise on the training codes (`--model.code-noise`, issue 12): the shipped model reconstructs its training objects
# far better than new ones (results/surface_errors_resolution_and_train.md: F@1cm 0.785 against 0.680), and a new
# object's code is the encoder's guess, so this asks whether a decoder trained on perturbed codes generalises
# better. Two runs side by side, one core each, each the same command and seed as a committed run without the noise
# (training is deterministic on one thread; a step costs the same with the noise):
#   scratch: the `small` preset from scratch, STEPS (9,000) steps; without the noise: affordance_weight.sh's λ 0.04
#            run (results/affordance_weight.json).
#   stage:   a further stage of the shipped weights with its own coarse field, 2e-4 -> 2e-5 over 10,450 steps,
#            stopped at 10,447; without the noise: fine_tune_shared_field.sh's "own" (results/fine_tune_shared_field.json).
# Then each calibrated (32 validation objects) and scored on val40 (side_by_side.sh), side by side.
#
#   DATA=/tmp/w/data WORK=/tmp/noise CACHE=/tmp/w/cache NOISE=0.2 benchmarks/code_noise.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
NOISE="${NOISE:-0.2}"
LIMIT="${MINUTES:-70}"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores
mkdir -p "$W"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh

warm_cache "$CACHE"
{
    timed_small_run scratch "${STEPS:-9000}" --cache-dir "$CACHE" --model.code-noise "$NOISE"
    calibrated_val40 scratch "$W/scratch"
} > "$W/scratch.log" 2>&1 &
{
    calibrated_stage stage src/affnerf/weights/affnerf-small.pt 10450 "$CACHE" --stop-at 10447 --val-every 0 \
        --model.coarse-field own --model.code-noise "$NOISE"
    val40 stage "$W/stage"
} > "$W/stage.log" 2>&1 &
wait
for name in scratch stage; do echo "== $name, code noise $NOISE"; sed -n 5,9p "$W/val40_$name/table2.md"; done
