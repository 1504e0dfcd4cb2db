#!/usr/bin/env bash
# How many positional-encoding frequencies of positions (issue 12; benchmarks/results/pe_frequencies.md). The field
# reads a point through sines and cosines of 2^k * pi * x, x in metres, k < pe_xyz (10 in both presets, the paper's
# value): the last octave has a 3.9 mm period, the spacing of the 128^3 meshes. Predicted meshes
# show ripples of about a centimetre (docs/overview.png, results/shared_3763.png), and a small conditional field
# asked to reproduce 512 objects through such inputs may fit them by detail that does not carry to new objects
# (Occupancy Networks, DISN and IF-Net use none; pixelNeRF six). Runs of the small preset from scratch, one core
# each, side by side, one per value of PES (default "10 7": as shipped, and a 3.1 cm shortest period), each ending
# by its step count (STEPS) or MINUTES, whichever is first; each is evaluated on 40 validation objects (5 per
# category, 5 target views at 100x75, meshes at 96^3).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/pe_frequencies}"
MINUTES="${MINUTES:-38}"
STEPS="${STEPS:-18000}"
PES="${PES:-10 7}"
export OMP_NUM_THREADS=1
LIMIT="$MINUTES"
# shellcheck source=benchmarks/side_by_side.sh
source benchmarks/side_by_side.sh
CACHE="${CACHE:-$W/cache}"
sweep_small_runs pe --model.pe-xyz "$PES"
