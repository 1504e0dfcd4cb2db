#!/usr/bin/env bash
# The wide field (capacity.md) with the shipped model's whole budget (benchmarks/results/wide_full_budget.md, issue 12):
# as the shipped model was trained, two single-threaded processes under torchrun (one per core), but one schedule of
# STEPS steps that ends with the minutes (1e-3 -> 2e-5, the shipped model's two stages' first and last rates), then
# every other checkpoint and the shipped model scored side by side on the ladder's 16 validation objects, and the
# last checkpoint's mesh level calibrated on 32 validation objects at 96^3 as the shipped model's was
# (calibration_shipped.json); last, both models side by side on 40 validation objects (5 per category, 5 target
# views at 100x75, 3D at 96^3; `affnerf eval --split val`). STEPS: 3.9 steps a second were measured on the 2-core
# machine, so 22,000 in 94 min. EXTRA: more training options, e.g. EXTRA="--precision bf16" (precision.md: the wide
# field 1.7x faster a step on this CPU), with WORK elsewhere and STEPS to match.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/wide_full_budget}"
MINUTES="${MINUTES:-100}"
STEPS="${STEPS:-22000}"
export OMP_NUM_THREADS=1
# shellcheck disable=SC2086  # EXTRA is a list of options
.venv/bin/torchrun --standalone --nproc_per_node 2 -m affnerf.cli.main train --data "$DATA" --out "$W/run" \
    --config small --steps "$STEPS" --time-limit "$MINUTES" --device cpu --checkpoint-every 2000 \
    --keep-checkpoints 100 --val-every 0 --cache-dir "${CACHE:-$W/cache}" --no-progress \
    --model.field-width 128 --model.color-width 64 --model.affordance-width 64 --optim.lr 1e-3 --optim.lr-final 2e-5 \
    ${EXTRA:-}
.venv/bin/python benchmarks/ablation_ladder.py --data "$DATA" --work "$W" --out "$W/score_wide.json" \
    --score-run "$W/run" --stride 2 &
{
    .venv/bin/python benchmarks/ablation_ladder.py --data "$DATA" --work "$W" --out "$W/score_shipped.json" \
        --reference src/affnerf/weights/affnerf-small.pt
    # stores the chosen level in the run's last checkpoint, ready for `python -m affnerf.predict.shipped`
    .venv/bin/affnerf eval calibrate --run "$W/run" --data "$DATA" --max-objects 32 --resolution 96 --device cpu
} &
wait
for m in wide shipped; do
    model="$W/run"; [ "$m" = shipped ] && model=src/affnerf/weights/affnerf-small.pt
    .venv/bin/affnerf eval --run "$model" --data "$DATA" --split val --method affnerf --scale 0.25 --target-views 5 \
        --max-objects 5 --mesh-resolution 96 --device cpu --out "$W/val_$m" &
done
wait
# everything above in one results file, W/wide_full_budget.json
.venv/bin/python - "$W" <<'PY'
import json
import sys

work = sys.argv[1]
load = lambda path: json.load(open(f"{work}/{path}"))  # noqa: E731
wide, shipped, summary = load("score_wide.json"), load("score_shipped.json"), load("run/summary.json")
calibration = load("run/calibration.json")
keep = ("split", "resolution", "levels", "optical_depths", "chosen_level", "chosen_optical_depth")
result = {
    "benchmark": "wide_full_budget",
    "machine": wide["machine"],
    "training": {
        "command": "benchmarks/wide_full_budget.sh (torchrun, 2 processes, one thread each)",
        "precision": load("run/config.json").get("precision", "fp32"),
        "steps": summary["step"],
        "seconds": summary["seconds"],
        "model": {"field_width": 128, "color_width": 64, "affordance_width": 64},
        "optim": {"lr": 1e-3, "lr_final": 2e-5},
    },
    "ladder": {
        "heldout_objects": wide["heldout_objects"],
        "wide": wide["runs"]["run"],
        "shipped": shipped["reference"],
    },
    "calibration_wide": {key: calibration[key] for key in keep},
    "validation_40": {
        model: {key: load(f"val_{model}/metrics_affnerf.json")[key] for key in ("mean", "settings")}
        for model in ("wide", "shipped")
    },
}
json.dump(result, open(f"{work}/wide_full_budget.json", "w"), indent=1)
PY
