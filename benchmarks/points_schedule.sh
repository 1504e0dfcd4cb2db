#!/usr/bin/env bash
# A scheduled weight of the 3D supervision (issue 12; benchmarks/results/points_schedule.md). points_weight.md found
# a 10x heavier occupancy term puts thin parts into the meshes (temples, handles, bails 1.7-3x as often) but costs
# the rendering 0.014 mIoU. Here, as further stages of the plain stage's length from the shipped weights
# (side_by_side.sh's scored_stage), the weight μ over a stage: each of STAGES is NAME:START:FINAL[:NU] (μ in a
# straight line from START to FINAL; FINAL -1 keeps START throughout; NU the points' affordance weight ν relative to
# their occupancy, 1 unless given). Two at a time, one per core, sharing one warm cache. The second pair of the
# results: STAGES="nu4:0.1:-1:4 early1.0to0.1_nu4:1.0:0.1:4"; the third, the training seed's share of the
# differences: SEED=1 STAGES="plain_seed1:0.1:-1 early1.0to0.1_seed1:1.0:0.1" (SEED: every stage's --seed).
# With TEST64="NAME=RUN ..." it trains nothing and scores those runs on the 64 test objects instead (side_by_side.sh's
# test64), two at a time, one per core.
#   DATA=... benchmarks/points_schedule.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/points_schedule}"
CACHE="${CACHE:-$W/cache}"
STAGES="${STAGES:-early1.0to0.1:1.0:0.1 pw0.3:0.3:-1}"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"
if [ -n "${TEST64:-}" ]; then
    i=0
    for pair in $TEST64; do
        (taskset -cp $((i % 2)) "$BASHPID" > /dev/null && OMP_NUM_THREADS=1 test64 "${pair%%=*}" "${pair#*=}") &
        i=$((i + 1))
        [ $((i % 2)) = 0 ] && wait
    done
    wait
    exit 0
fi
warm_cache "$CACHE" --points-weight 0.1

i=0
for stage in $STAGES; do
    IFS=: read -r name start final nu <<< "$stage"
    scored_stage "$name" $((i % 2)) "$CACHE" --points-weight "$start" --points-weight-final "$final" \
        --point-affordance-weight "${nu:-1}" --seed "${SEED:-0}" > "$W/$name.log" 2>&1 &
    i=$((i + 1))
    [ $((i % 2)) = 0 ] && wait
done
wait
