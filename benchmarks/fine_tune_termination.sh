#!/usr/bin/env bash
# Does placing each ray's weight on the true surface sharpen the model? (benchmarks/results/fine_tune_termination.md,
# issue 12). The shipped model's outlines are 1.3x the true area (silhouette_area.py); the depth L1 made them
# thicker (fine_tune_losses.md) because a ray can only raise its rendered depth by adding weight. The termination
# term (--termination-weight: the mean of Σ w·|t − depth| over object rays) cannot be lowered by adding weight and
# costs every bit of weight in front of or behind the surface, the halo included. A further stage with it at
# weight 1.0 against the same stage without, side by side (benchmarks/further_stage.sh), 8,500 steps each (the
# term costs nothing measurable a step).
set -euo pipefail
cd "$(dirname "$0")/.."
export WORK="${WORK:-benchmarks/.work/fine_tune_termination}"
exec benchmarks/further_stage.sh termination "${TERMINATION_STEPS:-8500}" --termination-weight "${WEIGHT:-1.0}"
