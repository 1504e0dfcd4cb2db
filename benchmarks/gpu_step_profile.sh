#!/usr/bin/env bash
# Where a training step of the small recipe spends its time on a GPU (issue 12): gpu_small_scale.sh found 10 steps
# a second per process on an H100 at 32 objects and 4,096 rays a step, with a field of 64 x 4 as with one of
# 128 x 6, so the step is not bound by the field's arithmetic. This profiles STEPS steps of that setting with
# cProfile (CUDA is asynchronous: GPU time shows up where Python waits for it, at the first synchronising call) on a
# small dataset, after a warm-up run that builds the caches, and writes the top of both orderings to $OUT.
#
#   OUT=... bash benchmarks/gpu_step_profile.sh     (on the lent machine; DEVICE=cpu PY=.venv/bin/python to try here)
set -uo pipefail
cd "$(dirname "$0")/.."
W="${WORK:-/tmp/gpu-profile}"
OUT="${OUT:-$W/out}"
PY="${PY:-python3}"
DEVICE="${DEVICE:-cuda}"
STEPS="${STEPS:-150}"
OBJECTS="${OBJECTS:-10}"
mkdir -p "$W" "$OUT"
# shellcheck source=benchmarks/gpu_env.sh
source benchmarks/gpu_env.sh
A data generate --out "$W/data" --objects-per-category "$OBJECTS" --views 30 --workers 16 \
    --seed 0 > "$W/data.log" 2>&1 || { tail -5 "$W/data.log"; exit 1; }
RUN=(--data "$W/data" --config small --objects-per-step 32 --rays-per-step 4096 --val-every 0 --log-every 50
    --checkpoint-every 100000 --no-progress --device "$DEVICE" --cache-dir "$W/cache")
A train "${RUN[@]}" --out "$W/warm" --steps 20 > "$W/warm.log" 2>&1 || { tail -5 "$W/warm.log"; exit 1; }
echo "data and caches in $(elapsed) s" | tee "$OUT/profile.txt"
"$PY" -m cProfile -o "$W/train.prof" -m affnerf.cli.main train "${RUN[@]}" --out "$W/prof" --steps "$STEPS" \
    >> "$OUT/profile.txt" 2>&1
tail -n 2 "$W/prof/metrics.jsonl" >> "$OUT/profile.txt"
"$PY" - "$W/train.prof" >> "$OUT/profile.txt" <<'PY'
import pstats
import sys

stats = pstats.Stats(sys.argv[1])
stats.sort_stats("tottime").print_stats(30)
stats.sort_stats("cumtime").print_stats("affnerf", 40)
PY
cat "$OUT/profile.txt"
