#!/usr/bin/env bash
# Does teaching the shape encoder to label its input crop's pixels help it see small parts? (issue 12;
# results/view_labels.md) A further stage from the shipped weights with the pixel-labelling head
# (--model.view-affordance-weight W, default 0.1) against the same stage without it, side by side, one core each,
# the same steps (STEPS; a fresh Adam, 2e-4 -> 2e-5) and point sets (version 4); each calibrated (32 validation
# objects), then val40 (which keeps per-class IoU), and the head's own labelling of validation crops
# (benchmarks/view_label_head.py). The stage without the head is fine_tune_outer_surface.sh's "outer" stage: pass
# its run folder as PLAIN_RUN to reuse it.
#   DATA=... [WORK=...] [STEPS=14000] [W_VIEW=0.1] [PLAIN_RUN=...] [INIT=...] benchmarks/fine_tune_view_labels.sh
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/fine_tune_view_labels}"
STEPS="${STEPS:-14000}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"
# the weights shipped when this ran (version-3 point sets; replaced since), unless INIT names others
SHIPPED="${INIT:-$W/shipped_v3.pt}"
[ -f "$SHIPPED" ] || git show ab24f38:src/affnerf/weights/affnerf-small.pt > "$SHIPPED"
SAVED=(--checkpoint-every 2000 --keep-checkpoints 100 --val-every 0)

warm_cache "$W/cache"
PLAIN="${PLAIN_RUN:-$W/plain}"
[ -n "${PLAIN_RUN:-}" ] || calibrated_stage plain "$SHIPPED" "$STEPS" "$W/cache" "${SAVED[@]}" > "$W/plain.log" 2>&1 &
calibrated_stage view_labels "$SHIPPED" "$STEPS" "$W/cache" "${SAVED[@]}" \
    --model.view-affordance-weight "${W_VIEW:-0.1}" > "$W/view_labels.log" 2>&1 &
wait
val40 plain "$PLAIN" &
val40 view_labels "$W/view_labels" &
wait
.venv/bin/python benchmarks/view_label_head.py --checkpoint "$W/view_labels" --data "$DATA" --cache-dir "$W/cache" \
    --out "$W/view_label_head.json"
