#!/usr/bin/env bash
# Is the encoders' input the limit? (benchmarks/results/encoder_size.md, issue 12). The small preset's encoders see a
# 64-pixel crop at a quarter of ResNet18's width; neither was ever varied (the preset search varied the field, and
# neither a wider field, wide_full_budget.md, nor a larger code, code_size.md, paid). Side by side, one core each,
# the same minutes: the small preset against encoders on 96-pixel crops, each with a schedule that ends when the
# minutes do (SMALL_STEPS, CROP_STEPS: 10,000 each, at the 9.4 and 9.0 steps a second measured here side by side);
# every checkpoint scored on the ladder's 16 validation objects.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/encoder_size}"
MINUTES="${MINUTES:-22}"
export OMP_NUM_THREADS=1
SMALL_STEPS="${SMALL_STEPS:-10000}"
CROP_STEPS="${CROP_STEPS:-10000}"
CROP=(--model.encoder-resolution 96)
LIMIT="$MINUTES"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
# build both frame caches (the crops depend on the encoder's resolution) before either run is timed
warm_cache "$W/cache_small"
warm_cache "$W/cache_crop96" "${CROP[@]}"
timed_small_run small "$SMALL_STEPS" --cache-dir "$W/cache_small" &
timed_small_run crop96 "$CROP_STEPS" --cache-dir "$W/cache_crop96" "${CROP[@]}" &
wait
score_runs small crop96
