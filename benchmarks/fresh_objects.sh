#!/usr/bin/env bash
# Score weights on objects drawn afresh (another dataset seed, never trained, validated or tested on): all
# splits of `affnerf data generate --objects-per-category 30 --views 8 --seed 11`, 24 objects per category
# = 192 objects, with val40's protocol otherwise (side_by_side.sh's protocol_eval): nearly five times val40's
# objects, to rank recipes whose val40 and test64 scores disagree (results/validation_size.md).
#   [FRESH=/tmp/fresh/data] [WORK=...] benchmarks/fresh_objects.sh NAME=WEIGHTS [NAME=WEIGHTS...]
# Two evaluations at a time, one thread each; writes W/fresh192_NAME (metrics.json, table2.md).
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${FRESH:-/tmp/fresh/data}"
W="${WORK:-benchmarks/.work/fresh_objects}"
export OMP_NUM_THREADS=1
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
mkdir -p "$W"
[ -f "$DATA/dataset.json" ] || .venv/bin/affnerf data generate --out "$DATA" --objects-per-category 30 --views 8 \
    --seed 11 --workers 2
for pair in "$@"; do
    out="$W/fresh192_${pair%%=*}"
    rm -rf "$out"
    protocol_eval all 24 0.25 "$out" "${pair#*=}" > "$out.log" 2>&1 &
    while [ "$(jobs -rp | wc -l)" -ge 2 ]; do wait -n || true; done
done
wait
for pair in "$@"; do
    out="$W/fresh192_${pair%%=*}"
    [ -f "$out/metrics.json" ] || { echo "fresh_objects.sh: ${pair%%=*} failed, see $out.log" >&2; exit 1; }
    echo "== ${pair%%=*}: $(grep "^affnerf: mIoU" "$out.log")"
done
