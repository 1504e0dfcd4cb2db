#!/usr/bin/env bash
# Two `small` runs side by side, one core each, each with its own training options, then both calibrated (32
# validation objects) and scored on val40 and, unless TEST64=0, on the 64 test objects, side by side.
# - From scratch (no INIT) on the 13,000-step schedule whose preset runs are preset_seeds.json's `pre_s0` / `pre_s1` /
#   `pre_s2` and part_edges.json's `preset_s0` / `preset_s1`: five runs of the same command that spread by 0.02-0.04
#   mIoU a split (results/preset_seeds.md), so read a pair against all of them, not one run a seed:
#   collect_stages.py gathers the pair, rank_scratch.py ranks it against every committed screen and the preset runs.
# - With INIT=WEIGHTS (a checkpoint, e.g. src/affnerf/weights/affnerf-small.pt): two further stages of those weights
#   (a fresh Adam, 2e-4 -> 2e-5 over STEPS), gathered in W/stage_pair.json beside the shipped weights' rows
#   (see results/lovasz_stage.md).
# - WARM_OPTIONS="--some-option V": build the point sets with these options before the pair (an option that
#   changes the point sets, such as --point-sigma-near, must be the same in A and B: the cache keeps one set an object).
#   DATA=... [WORK=...] [CACHE=...] [STEPS=13000] [TEST64=1] [INIT=...] [WARM_OPTIONS=...] \
#       A="NAME --seed 0 --some-option V" B="NAME --seed 1 --some-option V" benchmarks/scratch_pair.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/scratch_pair}"
LIMIT="${LIMIT:-60}"  # a safety net: the runs end on their step count
STEPS="${STEPS:-13000}"
CACHE="${CACHE:-$W/cache}"
read -r -a first <<< "${A:?A=\"NAME [TRAIN OPTIONS...]\"}"
read -r -a second <<< "${B:?B=\"NAME [TRAIN OPTIONS...]\"}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
if [ -n "${INIT:-}" ]; then
    warm_cache "$CACHE"
    scored_further_stage "${first[0]}" "$INIT" "$STEPS" "$CACHE" --time-limit "$LIMIT" "${first[@]:1}" &
    scored_further_stage "${second[0]}" "$INIT" "$STEPS" "$CACHE" --time-limit "$LIMIT" "${second[@]:1}" &
    wait
    .venv/bin/python benchmarks/collect_stages.py --work "$W" --names "${first[0]}" "${second[0]}" --compact \
        --reference benchmarks/results/retrain_keypoints.json:run:shipped --out "$W/stage_pair.json"
    exit 0
fi
scored_pair "${first[0]}" "$STEPS" "${first[@]:1}" -- "${second[0]}" "$STEPS" "${second[@]:1}"
if [ "${TEST64:-1}" = 1 ]; then
    test64 "${first[0]}" "$W/${first[0]}" &
    test64 "${second[0]}" "$W/${second[0]}" &
    wait
fi
