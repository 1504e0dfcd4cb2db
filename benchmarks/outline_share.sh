#!/usr/bin/env bash
# Other shares and radii of the outline rays (issue 12; results/outline_share.md): the `small` preset from scratch
# with a quarter of the rays near the outline (radius 3 px, keeping a quarter uniform for the large objects that
# lost in outline_rays.md) and with the preset's 0.4 in a band twice as wide (radius 6 px), side by side, one core
# each, 15,000 steps as outline_rays.sh; then both calibrated and scored on val40 and the 64 test objects
# (scratch_pair.sh runs them). The preset's own rows (0.4 at 3 px, and no outline rays) are outline_rays.sh's
# seed-0 runs: training and scoring are deterministic here, so they are not trained again.
#   DATA=... [WORK=...] [CACHE=...] [SEED=0] benchmarks/outline_share.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export SEED="${SEED:-0}"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
tag=$(seed_tag)
A="share0.25$tag --seed $SEED --outline-fraction 0.25 --outline-radius 3" \
    B="radius6$tag --seed $SEED --outline-fraction 0.4 --outline-radius 6" \
    STEPS="${STEPS:-15000}" LIMIT="${LIMIT:-75}" WORK="${WORK:-benchmarks/.work/outline_share}" \
    exec benchmarks/scratch_pair.sh
