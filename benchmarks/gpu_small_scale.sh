#!/usr/bin/env bash
# The small recipe with a GPU's compute (issue 12), in one command that fits a 10-minute slot of a lent GPU:
# is the CPU model held back by its training budget, or by its size? Two runs side by side on one GPU for the same
# wall time, each with 32 objects and 4,096 rays a step (128 rays an object, 4 times the CPU preset's 32); RUNS
# names them (default "stage wide"):
#   stage  a further stage of the shipped weights (its architecture; a fresh Adam, 2e-4 -> 2e-5), as the shipped
#          model's own second stage, with far more rays;
#   narrow from scratch (1e-3 -> 2e-5), the small preset as it is (field 64 x 4);
#   wide   from scratch, the small preset with a field of 128 x 6 (colour and affordance heads 64) instead of
#          64 x 4: the capacity that did not pay at equal CPU time (results/wide_full_budget.md);
#   wider  from scratch, the paper's field (256 x 8, heads 128) on the small preset's encoders.
# Then each run, and the shipped weights, are scored on the val40 protocol of side_by_side.sh (40 validation objects, input view 0, 5 targets at 100x75, meshes at 96^3),
# on the GPU, at the mesh level stored in the weights (CAL_OBJECTS > 0 calibrates each run first; at about 4 s an
# object that does not fit the slot, so the runs' levels are calibrated afterwards on a CPU). Everything small comes back in $OUT/gpu_small_scale.tar.gz, and each run's last weights as
# $OUT/<run>.pt (without the optimiser, as the shipped file) so they can be scored again on a CPU.
#
#   OUT=... bash benchmarks/gpu_small_scale.sh        (on the lent machine; BUDGET=seconds of the whole command)
#
# Needs python3 with CUDA torch, and the wheels named in benchmarks/README.md in .whl/ when the machine lacks them.
set -uo pipefail
cd "$(dirname "$0")/.."
W="${WORK:-/tmp/gpu}"
OUT="${OUT:-$W/out}"
PY="${PY:-python3}"
DEVICE="${DEVICE:-cuda}"
OBJECTS="${OBJECTS:-80}"        # objects per category (80: the dataset of every committed table)
WORKERS="${WORKERS:-16}"
BUDGET="${BUDGET:-570}"         # seconds the whole command may take; training ends EVAL_S before
EVAL_S="${EVAL_S:-110}"         # seconds kept for scoring and packing
PROBE_STEPS="${PROBE_STEPS:-60}"
VAL_OBJECTS="${VAL_OBJECTS:-5}" # validation objects per category in val40
CAL_OBJECTS="${CAL_OBJECTS:-0}" # validation objects to calibrate the mesh level on (0: keep the stored level;
                                # val40 took 14 s on an H100, so 32 likely fits beside it: untimed)
TARGETS="${TARGETS:-5}"         # target views per object in val40
RUNS="${RUNS:-stage wide}"      # the runs trained side by side (names above)
SCORE="${SCORE:-1}"             # 0: no val40 on the GPU (the weights come back to be scored on a CPU)
mkdir -p "$W" "$OUT"

# shellcheck source=benchmarks/gpu_env.sh
source benchmarks/gpu_env.sh
D="${DATA:-$W/data}"
CACHE="$W/cache"
SHIPPED=src/affnerf/weights/affnerf-small.pt
COMMON=(--config small --objects-per-step 32 --rays-per-step 4096 --val-every 0 --log-every 20 --checkpoint-every 1000
    --keep-checkpoints 2 --no-progress --device "$DEVICE" --cache-dir "$CACHE")
STAGE=("${COMMON[@]}" --init-from "$SHIPPED" --optim.lr 2e-4 --optim.lr-final 2e-5)
NARROW=("${COMMON[@]}")
WIDE=("${COMMON[@]}" --model.field-width 128 --model.field-depth 6 --model.color-width 64 --model.affordance-width 64)
WIDER=("${COMMON[@]}" --model.field-width 256 --model.field-depth 8 --model.color-width 128 --model.affordance-width 128)
for r in $RUNS; do  # each run's arguments are the array named as the run in capitals
    case "$r" in stage | narrow | wide | wider) ;; *) echo "unknown run $r (stage, narrow, wide, wider)" >&2; exit 2 ;; esac
done
train() {  # train RUN OUT [ARGS...]: one run with its arguments and more
    local run=$1 out=$2; shift 2
    local -n a="${run^^}"
    A train --data "$D" --out "$out" "${a[@]}" "$@"
}

pack() {
    tar -czf "$OUT/gpu_small_scale.tar.gz" -C "$W" --exclude='*/checkpoints' --exclude='*/tb' --exclude='*.npy' \
        --exclude='*.npz' --exclude=./data --exclude=./cache --exclude=./out . 2>/dev/null
}

rate() {  # steps per second a probe kept after its first logged window (start-up), times 0.8 for the slowdown seen
    "$PY" -c "import json,sys; m=[json.loads(l) for l in open(sys.argv[1])]
print(0.8 * min(x['perf/rays_per_second'] for x in (m[1:] or m)) / 4096)" "$1/metrics.jsonl"
}

{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv 2>&1
  "$PY" -c "import torch; print('torch', torch.__version__, 'cuda', torch.cuda.is_available())"; } | tee "$OUT/device.txt"
[ -f "$D/dataset.json" ] || A data generate --out "$D" --objects-per-category "$OBJECTS" --views 30 \
    --workers "$WORKERS" --seed 0 > "$W/data.log" 2>&1 || { tail -5 "$W/data.log"; exit 1; }
echo "data at $(elapsed) s" | tee -a "$OUT/device.txt"
# frame caches and point sets before anything is timed: one process per category, one step each
for c in screwdriver pen scissors eyeglasses bucket bottle cabinet teapot; do
    A train --data "$D" --out "$W/warm-$c" "${COMMON[@]}" --steps 1 --objects-per-step 2 --rays-per-step 64 \
        --categories "$c" > "$W/warm-$c.log" 2>&1 &
done
wait
echo "caches at $(elapsed) s" | tee -a "$OUT/device.txt"
# speed probe, all side by side
for r in $RUNS; do train "$r" "$W/probe-$r" --steps "$PROBE_STEPS" > "$W/probe-$r.log" 2>&1 & done
wait
MINUTES=$("$PY" -c "print(round(max(0.5, ($BUDGET - $EVAL_S - $(elapsed) - 15) / 60), 2))")
for r in $RUNS; do
    "$PY" -c "import sys; print(max(20, int(float(sys.argv[1]) * 60 * $MINUTES)))" "$(rate "$W/probe-$r")" \
        > "$W/steps-$r" || { tail -5 "$W/probe-$r.log"; exit 1; }
    echo "$r: $(rate "$W/probe-$r") steps/s -> $(cat "$W/steps-$r") steps in $MINUTES min" | tee -a "$OUT/device.txt"
done
for r in $RUNS; do
    train "$r" "$W/$r" --steps "$(cat "$W/steps-$r")" --time-limit "$MINUTES" > "$W/train-$r.log" 2>&1 &
done
wait
echo "training done at $(elapsed) s" | tee -a "$OUT/device.txt"
for r in $RUNS; do tail -n 2 "$W/train-$r.log"; done
weights() {  # each run's last checkpoint to $OUT, as the shipped model was exported (again after calibration,
    # which stores the mesh level in it)
    for r in $RUNS; do
        "$PY" -m affnerf.predict.shipped "$W/$r" "$OUT/$r.pt" || echo "no weights of $r"
    done
}
weights
pack
left() { echo $((BUDGET - 10 - $(elapsed))); }
score() {  # score NAME RUN: calibrate a run folder (not the shipped file, calibrated already), then val40
    if [ -d "$2" ] && [ "$CAL_OBJECTS" -gt 0 ]; then
        timeout "$(left)" "${AFF[@]}" eval calibrate \
            --run "$2" --data "$D" --max-objects "$CAL_OBJECTS" --device "$DEVICE" > "$W/calibrate-$1.log" 2>&1
    fi
    timeout "$(left)" "${AFF[@]}" eval --run "$2" \
        --data "$D" --split val --method affnerf --scale 0.25 --target-views "$TARGETS" --max-objects "$VAL_OBJECTS" \
        --mesh-resolution 96 --device "$DEVICE" --chunk 16384 --out "$W/val40_$1" > "$W/val40-$1.log" 2>&1
}
[ "$SCORE" = 1 ] || exit 0
for r in $RUNS; do score "$r" "$W/$r" & done
score shipped "$SHIPPED" &
wait
echo "scoring done at $(elapsed) s" | tee -a "$OUT/device.txt"
weights
pack
for r in shipped $RUNS; do echo "== $r"; cat "$W/val40_$r/table2.md" 2>/dev/null | head -20; done
