#!/usr/bin/env bash
# Are the encoders too narrow? (benchmarks/results/encoder_width.md, issue 12). The small preset's two ResNet18s run
# at a quarter of the standard width (16-32-64-128 channels); a wider field (wide_full_budget.md), a larger code
# (code_size.md) and a larger crop (encoder_size.md) did not pay, so the encoders' width is the last part of the
# model never varied. Side by side, one core each, the same minutes: the small preset against encoders at half
# width, each with a schedule that ends when the minutes do (SMALL_STEPS, WIDE_STEPS: 10,000 and 8,300, at the 9.2
# and 7.6 steps a second measured here side by side); every checkpoint scored on the ladder's 16 validation objects.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/encoder_width}"
MINUTES="${MINUTES:-22}"
export OMP_NUM_THREADS=1
SMALL_STEPS="${SMALL_STEPS:-10000}"
WIDE_STEPS="${WIDE_STEPS:-8300}"
LIMIT="$MINUTES"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
# build the frame and point cache before either run is timed (the encoders' width does not change the crops)
warm_cache "$W/cache"
timed_small_run small "$SMALL_STEPS" --cache-dir "$W/cache" &
timed_small_run enc050 "$WIDE_STEPS" --cache-dir "$W/cache" --model.encoder-width 0.5 &
wait
score_runs small enc050
