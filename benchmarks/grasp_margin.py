"""Choose a planner setting of ``affnerf eval grasp`` on validation objects (issue 13): the part margin
(``--part-margin``, ``PlanConfig.part_margin``), the width clearance on predicted models (``--predicted-clearance``,
``PlanConfig.width_clearance``) or the least label confidence of restricted grasps on predicted models
(``--min-confidence``, ``PlanConfig.min_confidence``). (Two more settings, ``--second-opinion`` and ``--sight-cone``,
measured in benchmarks/results/grasp_second_opinion.md and grasp_sight.md, were removed with their options: see
those files' provenance.)

Runs ``affnerf eval grasp`` on the validation split (no pictures; no physics unless ``--lift``) once per value, two
runs at a time on one thread each, and tabulates, per value, the share of task-part grasps with both contacts on the
true part (on the true and on the predicted mesh), objects left without a grasp, epsilon relative to the whole
surface and, with ``--lift``, lift and lift-and-disturb success of every condition. The value is chosen here, never
on the test split that Table 3 reports.

Usage::

    python benchmarks/grasp_margin.py --data DATA --out benchmarks/.work/margin \
        --values 0 0.005 0.01 0.015 0.02 --max-objects 5
    python benchmarks/grasp_margin.py --data DATA --out benchmarks/.work/clearance --setting predicted-clearance \
        --values 0.004 0.015 0.025 --lift --results benchmarks/results/grasp_clearance
    python benchmarks/grasp_margin.py --data DATA --out benchmarks/.work/confidence --setting min-confidence \
        --values 0 0.8 0.9 0.95 --results benchmarks/results/grasp_confidence
    python benchmarks/grasp_margin.py --data DATA --out benchmarks/.work/margin_seed1 --values 0 0.01 --seed 1
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
PHYSICS_CONDITIONS = ("true_whole", "true_part", "predicted_whole", "predicted_part")
TITLES = {
    "part-margin": "Part margin of restricted grasps",
    "predicted-clearance": "Width clearance on predicted models",
    "min-confidence": "Least label confidence of restricted grasps on predicted models",
}
#: Unit of each setting's values in the tables.
UNITS = {"part-margin": " (m)", "predicted-clearance": " (m)", "min-confidence": ""}


def run_one(args: argparse.Namespace, margin: float) -> tuple[float, Path, float | None]:
    """One ``eval grasp`` with the setting at ``margin`` (skipped when its folder holds results); returns (the
    value, its output folder, seconds or None when skipped)."""
    out = Path(args.out) / f"{args.setting}_{margin:g}_seed{args.seed}"
    if not (out / "grasp_metrics.json").is_file():
        cmd = [str(Path(sys.executable).parent / "affnerf")]
        cmd += ["eval", "grasp", "--run", args.run, "--data", args.data, "--out", str(out), "--split", args.split]
        cmd += ["--max-objects", str(args.max_objects), "--no-pictures", "--device", "cpu"]
        cmd += [] if args.lift else ["--no-lift"]
        cmd += [f"--{args.setting}", str(margin), "--seed", str(args.seed)]
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
    row["physics"] = {
        cond: {k: metrics["mean"][cond][k] for k in ("lift_success", "disturb_success")}
        for cond in PHYSICS_CONDITIONS
        if metrics["mean"][cond].get("lift_success") is not None
    }
    return row


def _pct(x: float | None) -> str:
    return "–" if x is None else f"{100 * x:.0f}%"


def markdown(rows: list[dict], provenance: str, setting: str = "part-margin") -> str:
    cats = list(rows[0]["predicted_part"]["on_part_share"])
    lines = [f"> {provenance}", "", f"# {TITLES[setting]}, chosen on validation objects", ""]
    for cond, title in (("predicted_part", "predicted from one image"), ("true_part", "true mesh")):
        lines += [f"**Share of task-part grasps with both contacts on the true task part, {title}**", ""]
        common = [k for k in cats if all(r[cond]["on_part_share"][k] is not None for r in rows)]
        name = setting.replace("-", " ") + UNITS[setting]
        lines += [f"| {name} | " + " | ".join(cats) + " | mean | mean, same categories | objects without grasps"]
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
        lines += ["", f"Same categories: {', '.join(common)} (every value has grasps there).", ""]
    return "\n".join(lines + physics_markdown(rows, setting))


def physics_markdown(rows: list[dict], setting: str) -> list[str]:
    """Lift and lift-and-disturb success per condition and value (mean over categories), when measured."""
    if not rows[0].get("physics"):
        return []
    conds = list(rows[0]["physics"])
    lines = ["**Physics: lift / lift-and-disturb success of the best grasps (mean over categories with grasps)**", ""]
    name = setting.replace("-", " ") + UNITS[setting]
    lines += [f"| {name} | " + " | ".join(c.replace("_", ", ") for c in conds) + " |"]
    lines += ["| --- " * (len(conds) + 1) + "|"]
    for r in rows:
        cells = [f"{_pct(r['physics'][c]['lift_success'])} / {_pct(r['physics'][c]['disturb_success'])}" for c in conds]
        lines += [f"| {r['margin']:g} | " + " | ".join(cells) + " |"]
    return lines + [""]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--run", default="src/affnerf/weights/affnerf-small.pt")
    parser.add_argument("--split", default="val")
    parser.add_argument("--setting", choices=sorted(TITLES), default="part-margin")
    parser.add_argument("--values", "--margins", type=float, nargs="+", default=[0.0, 0.005, 0.01, 0.015, 0.02])
    parser.add_argument("--seed", type=int, default=0, help="eval grasp's seed (input view and planner)")
    parser.add_argument("--lift", action="store_true", help="also run the physics lift and disturbance")
    parser.add_argument("--max-objects", type=int, default=5)
    parser.add_argument("--results", default="benchmarks/results/grasp_margin")
    parser.add_argument("--provenance", default="")
    args = parser.parse_args()
    with ThreadPoolExecutor(2) as pool:
        done = list(pool.map(lambda m: run_one(args, m), args.values))
    rows = [summarise(*d) for d in done]
    Path(args.results + ".json").write_text(json.dumps({"settings": vars(args), "rows": rows}, indent=1))
    report = markdown(rows, args.provenance, args.setting)
    Path(args.results + ".md").write_text(report)
    print(report)


if __name__ == "__main__":
    main()
