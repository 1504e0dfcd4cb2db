#!/usr/bin/env bash
# A signed-distance field (issue 12; --model.geometry sdf, VolSDF's density): surface_errors.md found hollow
# objects filled and thin parts (bails, handles, temples) missing, and the occupancy target tells a point near them
# only that it is outside. Two `small` runs from scratch side by side (one core each) with the preset's schedule for
# the same steps or MINUTES: "plain" (the preset) and "sdf" (the same with a signed-distance field trained towards
# each point's truncated distance at --point-distance-weight DISTANCE_WEIGHT). Then both are calibrated (32
# validation objects) and scored on val40 (side_by_side.sh) and by surface_errors.py (5 test objects a category).
#
#   DATA=/tmp/w/data WORK=/tmp/sdf [CACHE=...] benchmarks/sdf_geometry.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
MINUTES="${MINUTES:-45}"
STEPS="${STEPS:-18000}"  # the schedule's length, about what one core makes in MINUTES beside another run
DISTANCE_WEIGHT="${DISTANCE_WEIGHT:-1.0}"
LIMIT="$MINUTES"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores
mkdir -p "$W"

# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
W="$W/warm-a" warm_cache "$CACHE" --categories bottle,bucket,cabinet,eyeglasses &
W="$W/warm-b" warm_cache "$CACHE" --categories pen,scissors,screwdriver,teapot &
wait
timed_small_run plain "$STEPS" --cache-dir "$CACHE" &
timed_small_run sdf "$STEPS" --cache-dir "$CACHE" --model.geometry sdf --point-distance-weight "$DISTANCE_WEIGHT" &
wait
for name in plain sdf; do
    (.venv/bin/affnerf eval calibrate --run "$W/$name" --data "$DATA" --max-objects 32 --device cpu &&
        val40 "$name" "$W/$name" &&
        .venv/bin/python benchmarks/surface_errors.py --data "$DATA" --run "$W/$name" \
            --out "$W/surface_errors_$name.json") > "$W/score_$name.log" 2>&1 &
done
wait
for name in plain sdf; do echo "== $name"; sed -n 5,9p "$W/val40_$name/table2.md"; done
