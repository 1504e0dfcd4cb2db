#!/usr/bin/env bash
# How far do two trainings of the same recipe land apart? (issue 12; benchmarks/results/seed_spread.md). Every
# ablation of the quality work compares single runs; this measures the spread of the small preset's 18,000-step
# schedule over training seeds (initialisation, data order, ray and point draws), with the runs of
# pe_frequencies.sh as the seed-0 reference. Runs of the small preset from scratch, one core each, side by side,
# one per seed of SEEDS (default "1 2"), each scored on 40 validation objects (5 per category, 5 target views at
# 100x75, meshes at 96^3).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/seed_spread}"
MINUTES="${MINUTES:-40}"
STEPS="${STEPS:-18000}"
SEEDS="${SEEDS:-1 2}"
export OMP_NUM_THREADS=1
LIMIT="$MINUTES"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
CACHE="${CACHE:-$W/cache}"
sweep_small_runs seed --seed "$SEEDS"
