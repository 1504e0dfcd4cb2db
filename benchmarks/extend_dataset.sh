#!/usr/bin/env bash
# A larger training set around a dataset (issue 12, "more data"): BIG links every object of DATA (in its split)
# and adds EXTRA new objects of each category, all of them in the training split. The generator seeds every object
# by its index, so objects 0..N-1 of a larger dataset are DATA's own and the new ones are N..N+EXTRA-1; DATA's
# validation and test objects stay where they were. Used by more_objects.sh.
#
#   benchmarks/extend_dataset.sh DATA BIG EXTRA     (WORKERS: generator processes, default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${1:?DATA: the dataset to extend}"
BIG="${2:?BIG: the folder of the larger dataset}"
EXTRA="${3:?EXTRA: new objects per category}"
read -r N SEED < <(.venv/bin/python -c "import json, sys; g = json.load(open(sys.argv[1]))['generation']
print(g['objects_per_category'], g['seed'])" "$DATA/dataset.json")
mkdir -p "$BIG"
for folder in "$DATA"/*/*/; do
    c=$(basename "$(dirname "$folder")")
    mkdir -p "$BIG/$c"
    [ -e "$BIG/$c/$(basename "$folder")" ] || ln -s "$(realpath "$folder")" "$BIG/$c/$(basename "$folder")"
done
.venv/bin/affnerf data generate --out "$BIG" --objects-per-category $((N + EXTRA)) --views 30 --seed "$SEED" \
    --workers "${WORKERS:-2}"
.venv/bin/python - "$DATA" "$BIG" <<'PY'
import json
import sys
from pathlib import Path

data, big = Path(sys.argv[1]), Path(sys.argv[2])
original = {o["id"]: o["split"] for o in json.loads((data / "dataset.json").read_text())["objects"]}
index = json.loads((big / "dataset.json").read_text())
for entry in index["objects"]:
    entry["split"] = original.get(entry["id"], "train")
    transforms = big / entry["path"] / "transforms.json"
    if entry["id"] not in original:
        meta = json.loads(transforms.read_text())
        if meta.get("split") != "train":
            meta["split"] = "train"
            transforms.write_text(json.dumps(meta, indent=1))
index["generation"]["note"] = f"objects of {data} in their splits, the others added to the training split"
(big / "dataset.json").write_text(json.dumps(index, indent=1))
print({s: sum(o["split"] == s for o in index["objects"]) for s in ("train", "val", "test")})
PY
