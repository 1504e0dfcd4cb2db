# Sourced by the benchmarks that train two `small` runs side by side, one core each, for the same minutes
# (capacity.sh, encoder_size.sh, encoder_width.sh, further_stage.sh, triplane.sh, batch_shape.sh, pe_frequencies.sh,
# seed_spread.sh, more_objects.sh, train_resolution.sh and the fine_tune_*.sh stages), and score them.
# Needs DATA, W and LIMIT (a run's time limit in minutes).
# shellcheck shell=bash

# seed_tag: the suffix of a run's name for the training seed SEED (none for seed 0, "_s1" for seed 1).
seed_tag() {
    [ "${SEED:-0}" = 0 ] || echo "_s$SEED"
}

# warm_cache CACHE [TRAIN OPTIONS...]: build the frame and point cache of DATA in CACHE (a one-step run in W/warm,
# with the options that change the crops or the point sets) before any run is timed, so no run pays for decoding.
# The run has WARM_NPROC single-threaded processes under torchrun (default 2, one a core), which share the objects.
# WARM_OPTIONS="--some-option V" adds options for every warm-up of a script (point sets that differ from the preset's).
warm_cache() {
    local cache=$1 warm_options=()
    shift
    read -r -a warm_options <<< "${WARM_OPTIONS:-}"
    set -- "$@" "${warm_options[@]}"
    rm -rf "$W/warm"
    OMP_NUM_THREADS=1 .venv/bin/torchrun --standalone --nproc_per_node "${WARM_NPROC:-2}" -m affnerf.cli.main train \
        --data "$DATA" --out "$W/warm" --config small --steps 1 --device cpu --val-every 0 --cache-dir "$cache" \
        --no-progress "$@"
}

# timed_small_run NAME STEPS [TRAIN OPTIONS...]: train W/NAME for STEPS steps (its schedule's length) or LIMIT
# minutes, whichever ends first, keeping a checkpoint every 1,000 steps for benchmarks/ablation_ladder.py.
timed_small_run() {
    local name=$1 steps=$2
    shift 2
    .venv/bin/python -m affnerf.cli.main train --data "$DATA" --out "$W/$name" --config small --steps "$steps" \
        --time-limit "$LIMIT" --device cpu --checkpoint-every 1000 --keep-checkpoints 100 --val-every 0 \
        --no-progress "$@"
}

# calibrated_stage NAME INIT STEPS CACHE [TRAIN OPTIONS...]: a further stage W/NAME from the weights INIT (a fresh
# Adam, 2e-4 -> 2e-5 over STEPS steps, frames and points in CACHE), then its mesh level calibrated on 32 validation
# objects (fine_tune_view_labels.sh, further_stage_outer_surface.sh, fine_tune_shared_field.sh). STAGE_NPROC=2
# trains it as two single-threaded processes under torchrun (both cores, 8 objects a step each), as a first stage is.
calibrated_stage() {
    local name=$1 init=$2 steps=$3 cache=$4
    shift 4
    local train=(.venv/bin/affnerf train)
    if [ "${STAGE_NPROC:-1}" -gt 1 ]; then
        train=(.venv/bin/torchrun --standalone --nproc_per_node "$STAGE_NPROC" -m affnerf.cli.main train)
    fi
    "${train[@]}" --data "$DATA" --out "$W/$name" --config small --steps "$steps" --init-from "$init" \
        --optim.lr 2e-4 --optim.lr-final 2e-5 --cache-dir "$cache" --device cpu --no-progress "$@"
    .venv/bin/affnerf eval calibrate --run "$W/$name" --data "$DATA" --max-objects 32 --device cpu
}

# scored_further_stage NAME INIT STEPS CACHE [TRAIN OPTIONS...]: calibrated_stage, then val40 and the 64 test
# objects of it side by side, as W/val40_NAME and W/test64_NAME (retrain_preset.sh, further_stage_candidate.sh,
# scratch_pair.sh with INIT).
scored_further_stage() {
    local name=$1
    calibrated_stage "$@"
    rm -rf "$W/val40_$name" "$W/test64_$name"
    val40 "$name" "$W/$name" &
    test64 "$name" "$W/$name" &
    wait
}

# score_runs NAME...: every checkpoint of each W/NAME on the ladder's validation objects, the runs side by side;
# writes W/score_NAME.json and all of them in one W/scores.json (the results file).
score_runs() {
    local name
    for name in "$@"; do
        .venv/bin/python benchmarks/ablation_ladder.py --data "$DATA" --work "$W" --out "$W/score_$name.json" \
            --score-run "$W/$name" &
    done
    wait
    .venv/bin/python - "$W" "$@" <<'PY'
import json
import sys

work, names = sys.argv[1], sys.argv[2:]
parts = [json.load(open(f"{work}/score_{name}.json")) for name in names]
merged = {**parts[0], "runs": {run: score for part in parts for run, score in part["runs"].items()}}
json.dump(merged, open(f"{work}/scores.json", "w"), indent=1)
PY
}

# sweep_small_runs PREFIX FLAG "VALUES": one timed small run per value, side by side, W/PREFIXVALUE trained with
# FLAG VALUE for STEPS steps (or LIMIT minutes) on the frame and point cache CACHE, then each scored by val40.
sweep_small_runs() {
    local prefix=$1 flag=$2 values=$3 value
    warm_cache "$CACHE"
    for value in $values; do
        timed_small_run "$prefix$value" "$STEPS" --cache-dir "$CACHE" "$flag" "$value" &
    done
    wait
    for value in $values; do
        val40 "$prefix$value" "$W/$prefix$value" &
    done
    wait
}

# protocol_eval SPLIT OBJECTS SCALE OUT RUN-OR-CHECKPOINT: AFF-NeRF on the first OBJECTS objects per category of
# DATA's SPLIT (input view 0, 5 target views at SCALE of the dataset's resolution, meshes at 96^3), written to OUT:
# the one protocol behind val40, test64, val64 and fresh_objects.sh.
protocol_eval() {
    .venv/bin/affnerf eval --run "$5" --data "$DATA" --split "$1" --method affnerf --scale "$3" --target-views 5 \
        --max-objects "$2" --mesh-resolution 96 --device cpu --out "$4"
}

# val40 NAME RUN-OR-CHECKPOINT: AFF-NeRF on 40 validation objects of DATA (5 per category, 100x75 or VAL40_SCALE of
# the dataset's resolution), written to W/val40_NAME.
val40() {
    protocol_eval val 5 "${VAL40_SCALE:-0.25}" "$W/val40_$1" "$2"
}

# scored_pair NAME_A STEPS_A [OPTIONS_A...] -- NAME_B STEPS_B [OPTIONS_B...]: the frame and point cache CACHE
# built (warm_cache, with WARM_OPTIONS), then W/NAME_A and W/NAME_B trained side by side (timed_small_run, on
# CACHE), then each calibrated and scored by val40, side by side (experts.sh, foreground_fraction.sh,
# outline_rays.sh).
scored_pair() {
    local first=()
    while [ "$1" != "--" ]; do
        first+=("$1")
        shift
    done
    shift
    warm_cache "$CACHE"
    timed_small_run "${first[0]}" "${first[1]}" --cache-dir "$CACHE" "${first[@]:2}" &
    timed_small_run "$1" "$2" --cache-dir "$CACHE" "${@:3}" &
    wait
    calibrated_val40 "${first[0]}" "$W/${first[0]}" &
    calibrated_val40 "$1" "$W/$1" &
    wait
}

# calibrated_val40 NAME RUN: RUN's mesh level calibrated on 32 validation objects (stored in its checkpoint), then
# val40 of it as W/val40_NAME (shared_field.sh, weight_average.sh, affordance_weight.sh).
calibrated_val40() {
    .venv/bin/affnerf eval calibrate --run "$2" --data "$DATA" --max-objects 32 --device cpu
    val40 "$1" "$2"
}

# test64 NAME RUN-OR-CHECKPOINT: val40's protocol on all 64 test objects of DATA (8 per category), to W/test64_NAME:
# a second, larger set of objects on which to check a difference val40 found.
test64() {
    protocol_eval test 8 0.25 "$W/test64_$1" "$2"
}

# val64 NAME RUN-OR-CHECKPOINT: val40's protocol on all 64 validation objects of DATA (8 per category), to
# W/val64_NAME: the larger set to choose a recipe on, the test objects kept for reporting
# (results/validation_size.md).
val64() {
    protocol_eval val 8 0.25 "$W/val64_$1" "$2"
}

# scored_stage NAME CORE CACHE [TRAIN OPTIONS...]: a further stage W/NAME from the shipped weights with the plain
# stage's schedule (fine_tune_jitter.sh: a fresh Adam, 2e-4 -> 2e-5 over 15,500 steps, stopped at 14,393) and the
# given options, single-threaded on core CORE (this subshell and all it starts) with its frame and point cache in
# CACHE; then calibrated (32 validation objects), val40, surface errors (surface_errors.py, 5 test objects per
# category, to W/surface_errors_NAME.json) and grasps on 5 validation objects of each of GRASP_CATEGORIES.
scored_stage() {
    local name=$1 run="$W/$1" cache=$3
    taskset -cp "$2" "$BASHPID" > /dev/null  # this subshell (start it with &) and all it starts
    export OMP_NUM_THREADS=1
    shift 3
    .venv/bin/affnerf train --data "$DATA" --out "$run" --config small --steps 15500 \
        --stop-at 14393 --device cpu --checkpoint-every 1000 --keep-checkpoints 100 --val-every 0 --no-progress \
        --init-from src/affnerf/weights/affnerf-small.pt --optim.lr 2e-4 --optim.lr-final 2e-5 --cache-dir "$cache" "$@"
    .venv/bin/affnerf eval calibrate --run "$run" --data "$DATA" --max-objects 32 --device cpu
    val40 "$name" "$run"
    .venv/bin/python benchmarks/surface_errors.py --data "$DATA" --run "$run" --methods affnerf \
        --out "$W/surface_errors_$name.json"
    .venv/bin/affnerf eval grasp --run "$run" --data "$DATA" --split val --max-objects 5 \
        --categories "${GRASP_CATEGORIES:-bucket,cabinet,teapot,eyeglasses}" --no-pictures --device cpu \
        --out "$W/grasp_$name"
}

# merge_scores OUT NAME...: the AFF-NeRF metrics of each W/NAME (an eval folder) in one JSON file OUT keyed by NAME,
# without confusion matrices (retrain_preset.sh, further_stage_candidate.sh).
merge_scores() {
    local out=$1
    shift
    .venv/bin/python - "$W" "$out" "$@" <<'PY'
import json
import sys


def without_confusion(value):
    if isinstance(value, dict):
        return {k: without_confusion(v) for k, v in value.items() if k != "confusion"}
    return value


work, out, names = sys.argv[1], sys.argv[2], sys.argv[3:]
scores = {name: without_confusion(json.load(open(f"{work}/{name}/metrics_affnerf.json"))) for name in names}
json.dump(scores, open(out, "w"), indent=1)
PY
}
