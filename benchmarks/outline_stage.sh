#!/usr/bin/env bash
# The outline rays (results/outline_rays.md: 0.4 of a step's rays near the object's outline, the `small` preset
# since 2026-12-01) given to the two strongest weights as a further stage, side by side, one core each (issue 12;
# results/outline_stage.md):
#   A: the committed candidate `benchmarks/candidates/affnerf-small-cosine.pt` (the preset as it is now, 94 minutes
#      of both cores from scratch) with the warm restart of further_stage_candidate.md (a fresh Adam, 6e-4 -> 2e-5
#      on the preset's cosine over 19,000 steps). The same command without outline rays is that file's 6e-4 row
#      (`benchmarks/candidates/affnerf-small-cosine-stage.pt`), so the pair differs only in the rays.
#   B: the shipped weights (a coarse field of their own, Adam's exponential fall) with the stage they had
#      (2e-4 -> 2e-5 over 19,000 steps).
# Each then calibrated (32 validation objects) and scored by val40 and the 64 test objects (side_by_side.sh).
#   DATA=... [WORK=...] [CACHE=...] benchmarks/outline_stage.sh
# The time limits are a safety net for a slow machine: both runs ended on their step count in the committed run.
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/outline_stage}"
CACHE="${CACHE:-$W/cache}"
mkdir -p "$W/A" "$W/B"
WORK="$W/A" CACHE="$CACHE" LRS="6e-4" STAGE_OPTIONS="--time-limit 88 --outline-fraction 0.4" \
    benchmarks/further_stage_candidate.sh > "$W/A/run.log" 2>&1 &
WORK="$W/B" CACHE="$CACHE" LRS="2e-4" INIT=src/affnerf/weights/affnerf-small.pt \
    STAGE_OPTIONS="--model.coarse-field own --optim.schedule exponential --optim.warmup-steps 0 --time-limit 80 --outline-fraction 0.4" \
    benchmarks/further_stage_candidate.sh > "$W/B/run.log" 2>&1 &
wait
tail -n 12 "$W/A/run.log" "$W/B/run.log"
