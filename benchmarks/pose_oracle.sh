#!/usr/bin/env bash
# What pixel-aligned features are worth with a right camera (issue 12; results/pose_oracle.md): the pose-aware model
# trained with the true input cameras (--model.kind pose-aware --model.projection-camera given, an oracle) beside the
# small preset (AFF-NeRF's global codes), both from scratch, one core each, for the same LIMIT minutes; each
# schedule (ORACLE_STEPS, SMALL_STEPS) sized to end inside it from a short timing run of both side by side. Then
# every checkpoint of both on the ladder's 16 validation objects (benchmarks/ablation_ladder.py: posed, so the
# oracle projects with the true camera), and benchmarks/pose_oracle.py: the oracle with the true camera, turned
# ones, the fitted camera of `affnerf predict` and its own camera head, beside the small run and the shipped model.
#   DATA=... [WORK=...] [CACHE=...] [LIMIT=55] [ORACLE_STEPS=...] [SMALL_STEPS=...] benchmarks/pose_oracle.sh
# SKIP_TRAINING=1 only scores.
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/pose_oracle}"
CACHE="${CACHE:-$W/cache}"
LIMIT="${LIMIT:-55}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"
ORACLE=(--model.kind pose-aware --model.projection-camera given)

if [ "${SKIP_TRAINING:-0}" != 1 ]; then
    warm_cache "$CACHE"
    timed_small_run oracle "${ORACLE_STEPS:?steps of the oracle schedule}" --cache-dir "$CACHE" "${ORACLE[@]}" &
    timed_small_run small "${SMALL_STEPS:?steps of the small schedule}" --cache-dir "$CACHE" &
    wait
fi
score_runs oracle small
.venv/bin/python benchmarks/pose_oracle.py --data "$DATA" --run "$W/oracle" --cameras true,az10,el10,fit \
    --reference "$W/small" --out "$W/pose_oracle_a.json" &
.venv/bin/python benchmarks/pose_oracle.py --data "$DATA" --run "$W/oracle" --cameras head,az20,el20 \
    --reference src/affnerf/weights/affnerf-small.pt --out "$W/pose_oracle_b.json" &
wait
