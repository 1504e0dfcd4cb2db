#!/usr/bin/env bash
# The average of the weights (issue 12, quality per CPU-minute; --optim.ema-decay): one `small` run from scratch
# for MINUTES of one core with an exponential moving average of its weights (decay DECAY), then the run's own final
# weights and their average, each calibrated (32 validation objects) and scored on val40 (side_by_side.sh) and by
# surface_errors.py. The two come from the same run at the same step, so the comparison is paired and costs no
# second training; the average's own cost is one fused update a step (about 1 ms on one core against ~250 ms).
#
#   DATA=/tmp/w/data WORK=/tmp/ema CACHE=... SEED=1 STEPS=12600 benchmarks/weight_average.sh
#
# Run it once per SEED (each in its own WORK, or the same one: the run folders are named by seed). EXTRA: more
# training options, with NAME naming the run (e.g. NAME=one EXTRA="--model.encoders one": its own weights and their
# average against another run's, side by side).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:?WORK: the work folder}"
CACHE="${CACHE:-$W/cache}"
MINUTES="${MINUTES:-46}"
LIMIT="$MINUTES"
SEED="${SEED:-1}"
DECAY="${DECAY:-0.9995}"
read -r -a EXTRA_ARGS <<< "${EXTRA:-}"
export OMP_NUM_THREADS=1  # one thread a run: two runs on two cores
mkdir -p "$W"

# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
warm_cache "$CACHE"
run="${NAME:-ema}_seed$SEED"
timed_small_run "$run" "${STEPS:?STEPS: the schedule, about the steps MINUTES allow}" --cache-dir "$CACHE" \
    --seed "$SEED" --optim.ema-decay "$DECAY" "${EXTRA_ARGS[@]}"
# the run's own weights: the last checkpoint without its average, in a run folder of their own
last=$(find "$W/$run/checkpoints" -name 'step_*.pt' | sort | tail -1)
mkdir -p "$W/${run}_raw/checkpoints"
.venv/bin/python - "$last" "$W/${run}_raw/checkpoints/$(basename "$last")" <<'PY'
import sys

import torch

data = torch.load(sys.argv[1], map_location="cpu", weights_only=True)
for key in ("ema", "ema_updates"):
    data.pop(key)
torch.save(data, sys.argv[2])
PY
cp "$W/$run/config.json" "$W/${run}_raw/"
# SCORE: which of the two to score (raw: the run's own weights, ema: their average); SURFACE_ERRORS=0 skips
# surface_errors.py
names=()
for which in ${SCORE:-raw ema}; do names+=("$run$([[ "$which" == raw ]] && echo _raw)"); done
for name in "${names[@]}"; do
    calibrated_val40 "$name" "$W/$name"
    [[ "${SURFACE_ERRORS:-1}" == 0 ]] || .venv/bin/python benchmarks/surface_errors.py --data "$DATA" \
        --run "$W/$name" --out "$W/surface_errors_$name.json"
done
for name in "${names[@]}"; do echo "== $name"; sed -n 5,9p "$W/val40_$name/table2.md"; done
