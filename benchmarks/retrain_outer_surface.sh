#!/usr/bin/env bash
# The shipped recipe's first stage trained from scratch on the version-4 (outer-surface) point sets, against the
# same stage trained on version-3 sets (issue 12; results/retrain_outer_surface.md). fine_tune_outer_surface.sh
# gave the shipped weights a further stage on either set and found them level; this asks whether labels and
# distances from hidden faces shape what a model learns from the start (pens' caps, hidden under which lay the
# barrel's faces, are found at an IoU of 0.15 on val40).
#   DATA=... [WORK=...] [REFERENCE=candidate.pt] benchmarks/retrain_outer_surface.sh
# The version-3 run is the candidate of results/sdf_recipe.md (the same command on the code of 89e3dc2, 83 minutes
# on this machine); its weights are read from that commit unless REFERENCE names them. Both are scored by val40
# side by side, one core each (the candidate keeps the calibration it was committed with; the new run is
# calibrated the same way first). SKIP_TRAINING=1 only evaluates.
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/retrain_outer_surface}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"
REFERENCE="${REFERENCE:-$W/candidate_v3.pt}"
[ -f "$REFERENCE" ] || git show 89e3dc2:benchmarks/candidates/affnerf-small-sdf.pt > "$REFERENCE"

if [ "${SKIP_TRAINING:-0}" != 1 ]; then
    # the shipped recipe's first stage (results/sdf_recipe.md), two single-threaded processes
    .venv/bin/torchrun --standalone --nproc_per_node 2 -m affnerf.cli.main train --data "$DATA" --out "$W/v4" \
        --config small --steps 29500 --cache-dir "$W/cache" --no-progress
    .venv/bin/affnerf eval calibrate --run "$W/v4" --data "$DATA" --max-objects 32 --device cpu
fi
rm -rf "$W/val40_v3" "$W/val40_v4"
val40 v3 "$REFERENCE" &
val40 v4 "$W/v4" &
wait
