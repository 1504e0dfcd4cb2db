#!/usr/bin/env bash
# Does input jitter make the model hold up on photos? (issues 12 and 16; benchmarks/results/fine_tune_jitter.md). The
# shipped model never saw a changed crop (its input_jitter is 0); in the ablation ladder, from scratch, the jitter did
# not pay on clean validation renders. Here a further stage from the shipped weights with --input-jitter STRENGTH
# (colour, framing, blur and noise of the encoders' crops, train/augment.py) against the same stage without
# (benchmarks/further_stage.sh: side by side, one core each, the same MINUTES), each given its own mesh level (eval
# calibrate); then both on 40 clean validation objects (val40), on the lighting and camera changes of
# photo_conditions.py (the test objects of PHOTO_CATEGORIES, 2 each, true masks; the thin tools, where overexposure
# hurt most) and on the first COMPOSITES cluttered composites of bench_segment.py (predictions with no flags and
# with --box), each pair side by side. SKIP_TRAINING=1 only evaluates.
#   DATA=... SEG_DATA=... benchmarks/fine_tune_jitter.sh
# SEG_DATA: affnerf data generate --out SEG_DATA --objects-per-category 10 --views 4 --seed 7 (bench_segment's).
set -euo pipefail
cd "$(dirname "$0")/.."
export DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
SEG_DATA="${SEG_DATA:?bench_segment.py data: affnerf data generate --objects-per-category 10 --views 4 --seed 7}"
export WORK="${WORK:-benchmarks/.work/fine_tune_jitter}" MINUTES="${MINUTES:-30}"
export PLAIN_STEPS="${PLAIN_STEPS:-15500}" OMP_NUM_THREADS=1
PHOTO_CATEGORIES="${PHOTO_CATEGORIES:-eyeglasses,scissors}"
COMPOSITES="${COMPOSITES:-12}"
W="$WORK"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh

if [ "${SKIP_TRAINING:-0}" != 1 ]; then
    SCORE=0 benchmarks/further_stage.sh jitter "${JITTER_STEPS:-15500}" --input-jitter "${STRENGTH:-1.0}"
    for name in plain jitter; do
        .venv/bin/affnerf eval calibrate --run "$W/$name" --data "$DATA" --max-objects 32 --device cpu &
    done
    wait
fi
rm -rf "$W"/val40_*
for name in plain jitter; do
    val40 "$name" "$W/$name" &
done
wait
for name in plain jitter; do
    .venv/bin/python benchmarks/photo_conditions.py --data "$DATA" --checkpoint "$W/$name" \
        --categories "$PHOTO_CATEGORIES" --out "$W/photo_conditions_$name.json" > "$W/photo_conditions_$name.log" 2>&1 &
done
wait
for name in plain jitter; do
    .venv/bin/python benchmarks/bench_segment.py --data "$SEG_DATA" --composites "$COMPOSITES" --checkpoint "$W/$name" \
        --out "$W/composites_$name.json" > "$W/composites_$name.log" 2>&1 &
done
wait
