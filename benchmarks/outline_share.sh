#!/usr/bin/env bash
# Other shares and radii of the outline rays (issue 12; results/outline_share.md): the `small` preset from scratch
# with a quarter of the rays near the outline (radius 3 px, keeping a quarter uniform for the large objects that
# lost in outline_rays.md) and with the preset's 0.4 in a band twice as wide (radius 6 px), side by side, one core
# each, 15,000 steps as outline_rays.sh; then both calibrated and scored on val40 and the 64 test objects. The
# preset's own rows (0.4 at 3 px, and no outline rays) are outline_rays.sh's seed-0 runs: training and scoring
# are deterministic here, so they are not trained again.
#   DATA=... [WORK=...] [CACHE=...] [SEED=0] benchmarks/outline_share.sh
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/outline_share}"
LIMIT="${LIMIT:-75}"  # a safety net: the runs end on their step count
STEPS="${STEPS:-15000}"
SEED="${SEED:-0}"
CACHE="${CACHE:-$W/cache}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
tag=$(seed_tag)
scored_pair "share0.25$tag" "$STEPS" --seed "$SEED" --outline-fraction 0.25 --outline-radius 3 -- \
    "radius6$tag" "$STEPS" --seed "$SEED" --outline-fraction 0.4 --outline-radius 6
test64 "share0.25$tag" "$W/share0.25$tag" &
test64 "radius6$tag" "$W/radius6$tag" &
wait
