"""Merge ``affnerf eval grasp`` folders of disjoint categories, run side by side (one per core), into the one
Table 3 of every category: every object is evaluated on its own, so the merge equals a single run.

    .venv/bin/python benchmarks/merge_grasps.py --parts OUT_A OUT_B --out OUT

Writes ``OUT/grasp_objects.json``, ``OUT/grasp_metrics.json`` and ``OUT/table3.md`` (settings of the first part,
its ``categories`` every part's, ``seconds`` the longest part: the wall time of the side-by-side run) and copies the
parts' ``grasps_<category>.png``.
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

from affnerf.eval.grasp_intervals import table3_summary
from affnerf.eval.grasp_table import table3_markdown
from affnerf.eval.protocol import merge_settings
from affnerf.fileio import write_json_atomic


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--parts", type=Path, nargs="+", required=True)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    objects = [o for p in args.parts for o in json.loads((p / "grasp_objects.json").read_text())]
    ids = [o["object_id"] for o in objects]
    if len(set(ids)) != len(ids):
        raise SystemExit("merge_grasps: the parts share objects; merge runs of disjoint categories")
    summary = table3_summary(objects)
    context = merge_settings([json.loads((p / "grasp_metrics.json").read_text())["settings"] for p in args.parts])
    args.out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(args.out / "grasp_objects.json", objects)
    write_json_atomic(args.out / "grasp_metrics.json", {**summary, "settings": context})
    (args.out / "table3.md").write_text(table3_markdown(summary, context))
    for part in args.parts:
        for picture in part.glob("grasps_*.png"):
            shutil.copy2(picture, args.out / picture.name)


if __name__ == "__main__":
    main()
