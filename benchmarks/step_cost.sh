#!/usr/bin/env bash
# The time a training step costs with two option sets of the `small` preset, measured side by side (one core each,
# the same seed, data and frame cache) so that the machine's noise falls on both alike: seconds a step from step
# 100 (after the caches and the warm-up of the allocator) to the last, from each run's metrics.jsonl.
#   DATA=... [WORK=...] [CACHE=...] [STEPS=700] A="NAME [TRAIN OPTIONS...]" B="NAME [TRAIN OPTIONS...]" \
#       benchmarks/step_cost.sh
# Writes W/step_cost.json (results/termination_step_cost.json is one).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${DATA:?dataset: affnerf data generate --objects-per-category 80 --views 30 --seed 0}"
W="${WORK:-benchmarks/.work/step_cost}"
STEPS="${STEPS:-700}"
CACHE="${CACHE:-$W/cache}"
read -r -a first <<< "${A:?A=\"NAME [TRAIN OPTIONS...]\"}"
read -r -a second <<< "${B:?B=\"NAME [TRAIN OPTIONS...]\"}"
export OMP_NUM_THREADS=1
mkdir -p "$W"
for run in first second; do
    declare -n opts="$run"
    rm -rf "${W:?}/${opts[0]}"
    .venv/bin/affnerf train --data "$DATA" --out "$W/${opts[0]}" --config small --steps "$STEPS" --device cpu \
        --checkpoint-every 0 --val-every 0 --cache-dir "$CACHE" --no-progress "${opts[@]:1}" \
        > "$W/${opts[0]}.log" 2>&1 &
done
wait
.venv/bin/python - "$W" "$STEPS" "${first[0]}" "${second[0]}" <<'PY'
import json
import sys
from pathlib import Path

from affnerf.environment import describe_machine

work, steps, names = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3:]
result = {"machine": describe_machine(), "steps": steps, "from_step": 100, "seconds_per_step": {}}
for name in names:
    rows = [json.loads(line) for line in (work / name / "metrics.jsonl").open()]
    at = {row["step"]: row["time/seconds"] for row in rows}
    result["seconds_per_step"][name] = (at[steps] - at[100]) / (steps - 100)
first, second = (result["seconds_per_step"][n] for n in names)
result["ratio"] = second / first
(work / "step_cost.json").write_text(json.dumps(result, indent=1) + "\n")
print(json.dumps(result, indent=1))
PY
