#!/usr/bin/env bash
# Weight experts at equal wall time (issue 12; benchmarks/results/experts.md): the `small` preset as it ships against
# the same preset with one trunk weight set per family mixed per object by a router on the shape code
# (`--model.experts 8`, affnerf/model/experts.py), from scratch, side by side, one core each, each with a schedule
# as long as the steps it takes in LIMIT minutes (a step of the experts run costs about 13 % more); then both
# calibrated and scored on val40.
#   DATA=... benchmarks/experts.sh      (LIMIT minutes; STEPS_PLAIN, STEPS_EXPERTS: the schedules' lengths)
# The option was removed after this measurement: run the script of commit 1bf62e4 in a checkout of it.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/experts}"
LIMIT="${LIMIT:-55}"
STEPS_PLAIN="${STEPS_PLAIN:-19500}"
STEPS_EXPERTS="${STEPS_EXPERTS:-17500}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
scored_pair plain "$STEPS_PLAIN" -- experts "$STEPS_EXPERTS" --model.experts 8
