"""Choose the planner's part margin (``PlanConfig.part_margin``) on validation objects (issue 13).

Runs ``affnerf eval grasp`` on the validation split (no physics, no pictures) once per margin, two runs at a time on
one thread each, and tabulates, per margin, the share of task-part grasps with both contacts on the true part (on the
true and on the predicted mesh), objects left without a grasp, and epsilon relative to the whole surface. The margin
is chosen here, never on the test split that Table 3 reports.

Usage::

    python benchmarks/grasp_margin.py --data DATA --out benchmarks/.work/margin \
        --margins 0 0.005 0.01 0.015 0.02 --max-objects 5
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

CONDITIONS = ("true_part", "predicted_part")


def run_one(args: argparse.Namespace, margin: float) -> tuple[float, Path, float | None]:
    """One ``eval grasp`` at ``margin`` (skipped when its folder holds results); returns (margin, its output
    folder, seconds or None when skipped)."""
    out = Path(args.out) / f"margin_{margin:g}"
    if not (out / "grasp_metrics.json").is_file():
        cmd = [str(Path(sys.executable).parent / "affnerf")]
        cmd += ["eval", "grasp", "--run", args.run, "--data", args.data, "--out", str(out), "--split", args.split]
        cmd += ["--max-objects", str(args.max_objects), "--no-lift", "--no-pictures", "--device", "cpu"]
        cmd += ["--part-margin", str(margin)]
        start = time.perf_counter()
        env = dict(os.environ, OMP_NUM_THREADS="1")
        subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
        return margin, out, time.perf_counter() - start
    return margin, out, None


def summarise(margin: float, folder: Path, seconds: float | None) -> dict:
    """The figures of one margin's run from its ``grasp_metrics.json``."""
    metrics = json.loads((folder / "grasp_metrics.json").read_text())
    row: dict = {"margin": margin, "seconds": None if seconds is None else round(seconds, 1)}
    for cond in CONDITIONS:
        per_cat = {c: v[cond] for c, v in metrics["categories"].items()}
        row[cond] = {
            "on_part_share": {c: v["on_part_share"] for c, v in per_cat.items()},
            "no_grasp_objects": sum(v["no_grasp_objects"] for v in per_cat.values()),
            "objects": sum(v["objects"] for v in per_cat.values()),
            "mean_on_part_share": metrics["mean"][cond]["on_part_share"],
            "mean_epsilon_ratio": metrics["mean"][cond]["epsilon_ratio"],
        }
    return row


def _pct(x: float | None) -> str:
    return "–" if x is None else f"{100 * x:.0f}%"


def markdown(rows: list[dict], provenance: str) -> str:
    cats = list(rows[0]["predicted_part"]["on_part_share"])
    lines = [f"> {provenance}", "", "# Part margin of restricted grasps, chosen on validation objects", ""]
    for cond, title in (("predicted_part", "predicted from one image"), ("true_part", "true mesh")):
        lines += [f"**Share of task-part grasps with both contacts on the true task part, {title}**", ""]
        common = [k for k in cats if all(r[cond]["on_part_share"][k] is not None for r in rows)]
        lines += ["| margin (m) | " + " | ".join(cats) + " | mean | mean, same categories | objects without grasps"]
        lines[-1] += " | ε ratio |"
        lines += ["| --- " * (len(cats) + 5) + "|"]
        for r in rows:
            c = r[cond]
            shares = " | ".join(_pct(c["on_part_share"][k]) for k in cats)
            same = sum(c["on_part_share"][k] for k in common) / max(len(common), 1)
            lines += [
                f"| {r['margin']:g} | {shares} | {_pct(c['mean_on_part_share'])} | {_pct(same)} | "
                f"{c['no_grasp_objects']}/{c['objects']} | {c['mean_epsilon_ratio']:.2f} |"
            ]
        lines += ["", f"Same categories: {', '.join(common)} (every margin has grasps there).", ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--run", default="src/affnerf/weights/affnerf-small.pt")
    parser.add_argument("--split", default="val")
    parser.add_argument("--margins", type=float, nargs="+", default=[0.0, 0.005, 0.01, 0.015, 0.02])
    parser.add_argument("--max-objects", type=int, default=5)
    parser.add_argument("--results", default="benchmarks/results/grasp_margin")
    parser.add_argument("--provenance", default="")
    args = parser.parse_args()
    with ThreadPoolExecutor(2) as pool:
        done = list(pool.map(lambda m: run_one(args, m), args.margins))
    rows = [summarise(*d) for d in done]
    Path(args.results + ".json").write_text(json.dumps({"settings": vars(args), "rows": rows}, indent=1))
    Path(args.results + ".md").write_text(markdown(rows, args.provenance))
    print(markdown(rows, args.provenance))


if __name__ == "__main__":
    main()
