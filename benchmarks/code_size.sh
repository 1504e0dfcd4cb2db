#!/usr/bin/env bash
# Code size at equal wall time (benchmarks/results/code_size.md): the small preset with 32-d codes (shipped) against
# 128-d codes, side by side, one core each, 20 minutes each, then every second checkpoint scored on 16 validation
# objects. Run before the field computed a global code's product once per object (commit "Field: a global code's
# product ..."); check out the commit before it to reproduce the step times of the 128-d run.
# Then the step time of the per-point and the factored code path, side by side, 3 minutes each (OLD_SRC: a checkout
# of the commit before the factored path, e.g. `git worktree add /tmp/old <commit>^`).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/code_size}"
export OMP_NUM_THREADS=1
run() {
    name=$1; minutes=$2; shift 2
    .venv/bin/python -m affnerf.cli.main train --data "$DATA" --out "$W/$name" --config small --steps 17000 \
        --time-limit "$minutes" --device cpu --checkpoint-every 500 --keep-checkpoints 100 --val-every 0 \
        --cache-dir "$W/cache" --no-progress "$@"
}
run code32 20 & run code128 20 --model.code-dim 128 & wait
for n in code32 code128; do
    .venv/bin/python benchmarks/ablation_ladder.py --data "$DATA" --work "$W" --out "$W/score_$n.json" \
        --score-run "$W/$n" --stride 2 &
done
wait
if [ -n "${OLD_SRC:-}" ]; then
    PYTHONPATH="$OLD_SRC" run speed-per-point 3 & PYTHONPATH=src run speed-factored 3 & wait
fi
