#!/usr/bin/env bash
# Does conditioning every layer pay once the model has learnt its shapes? (benchmarks/results/fine_tune_film.md,
# issue 12). The ablation ladder measured FiLM only in the first ~800 steps (7 minutes a rung). No part of the
# network's size holds the model back (capacity.md, code_size.md, encoder_width.md), while it still fits its own
# training objects poorly: the question left is how the field uses its code. A concatenating field grows into a
# FiLM one exactly (the modulation starts at zero; affnerf train --init-from), so the shipped weights are the start:
# a further stage as it is against the same stage with FiLM, side by side (benchmarks/further_stage.sh), 17 minutes;
# FiLM steps cost twice as much here (5.2 against 10.4 steps a second measured side by side), hence 4,600 steps.
set -euo pipefail
cd "$(dirname "$0")/.."
export MINUTES="${MINUTES:-17}"
export WORK="${WORK:-benchmarks/.work/fine_tune_film}"
exec benchmarks/further_stage.sh film "${FILM_STEPS:-4600}" --model.conditioning film
