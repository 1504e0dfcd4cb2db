#!/usr/bin/env bash
# Score weights on objects drawn afresh (another dataset seed, never trained, validated or tested on): all
# splits of `affnerf data generate --objects-per-category 30 --views 8 --seed 11`, 24 objects per category
# = 192 objects, with val40's protocol otherwise (input view 0, 5 target views at 100x75, meshes at 96^3): nearly
# five times val40's objects, to rank recipes whose val40 and test64 scores disagree (results/validation_size.md).
#   [FRESH=/tmp/fresh/data] [WORK=...] benchmarks/fresh_objects.sh NAME=WEIGHTS [NAME=WEIGHTS...]
# Two evaluations at a time, one thread each; writes W/fresh192_NAME (metrics.json, table2.md).
set -euo pipefail
cd "$(dirname "$0")/.."
FRESH="${FRESH:-/tmp/fresh/data}"
W="${WORK:-benchmarks/.work/fresh_objects}"
export OMP_NUM_THREADS=1
mkdir -p "$W"
[ -f "$FRESH/dataset.json" ] || .venv/bin/affnerf data generate --out "$FRESH" --objects-per-category 30 --views 8 \
    --seed 11 --workers 2
running=0
failed=0
for pair in "$@"; do
    name="${pair%%=*}"
    rm -rf "$W/fresh192_$name"
    .venv/bin/affnerf eval --run "${pair#*=}" --data "$FRESH" --split all --method affnerf --scale 0.25 \
        --target-views 5 --max-objects 24 --mesh-resolution 96 --device cpu --out "$W/fresh192_$name" \
        > "$W/fresh192_$name.log" 2>&1 &
    running=$((running + 1))
    if [ "$running" -ge 2 ]; then
        wait -n || failed=1
        running=$((running - 1))
    fi
done
while [ "$running" -gt 0 ]; do
    wait -n || failed=1
    running=$((running - 1))
done
for pair in "$@"; do
    echo "== ${pair%%=*}"
    tail -2 "$W/fresh192_${pair%%=*}.log" | head -1
done
[ "$failed" = 0 ] || { echo "an evaluation failed: see $W/fresh192_*.log" >&2; exit 1; }
