"""Rank every from-scratch screen of the `small` preset's 13,000-step schedule against the preset's own runs.

Reads the committed results (`benchmarks/results/*.json` with a ``runs`` table, as `collect_stages.py` writes them),
keeps each run trained for 13,000 steps that was scored on both val40 and test64 (a run filed in several files
counts once), and prints a Markdown table sorted by val40 + test64 mIoU, with the preset runs named by
``--preset FILE:RUN`` marked and their range given, so a candidate is read against the spread of the preset itself
rather than against one run of it (results/preset_seeds.md). ``--also-steps N`` adds the runs of another step
count, each labelled with it: a screen whose steps cost more, run for about the preset's time (the 11,000 steps of 16
objects a step, results/objects_termination.md).

    python benchmarks/rank_scratch.py --preset preset_seeds.json:pre_s0 ... [--also-steps 11000] [--out TABLE.md]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
STEPS = 13_000
#: the means shown, each for val40 then test64, with their headers.
COLUMNS = {"mIoU": "mIoU", "MPA": "MPA", "PSNR": "PSNR", "fscore_1cm": "F@1cm", "affordance_miou_3d": "3D aff. mIoU"}


def scratch_runs(results: Path = RESULTS, steps: frozenset[int] = frozenset({STEPS})) -> dict[tuple[str, str], dict]:
    """(file name, run name) -> run, for every run of one of ``steps`` scored on val40 and test64, each run once
    (two files holding the same scores, as a reference copied beside a screen, give the first file's name)."""
    found: dict[tuple[str, str], dict] = {}
    seen: set[tuple[float, float]] = set()
    for path in sorted(results.glob("*.json")):
        data = json.loads(path.read_text())
        runs = data.get("runs") if isinstance(data, dict) else None
        if not isinstance(runs, dict):
            continue
        for name, run in runs.items():
            if not isinstance(run, dict) or run.get("steps") not in steps:
                continue
            if not all(isinstance(run.get(split), dict) for split in ("val40", "test64")):
                continue
            key = scores(run)
            if key not in seen:
                seen.add(key)
                found[(path.name, name)] = run
    return found


def scores(run: dict) -> tuple[float, float]:
    """A run's (val40, test64) mIoU, which names it across files."""
    return run["val40"]["mean"]["mIoU"], run["test64"]["mean"]["mIoU"]


def total(run: dict) -> float:
    """val40 + test64 mIoU, the sort key."""
    return run["val40"]["mean"]["mIoU"] + run["test64"]["mean"]["mIoU"]


def table(runs: dict[tuple[str, str], dict], presets: set[tuple[float, float]]) -> str:
    """The Markdown ranking, the runs whose :func:`scores` are in ``presets`` in bold, and a line with the preset
    runs' range of the sort key."""
    head = " | ".join(f"val40 {h} | test64 {h}" for h in COLUMNS.values())
    lines = [f"| run | {head} | sum of mIoU |", "| --- |" + " --- |" * (2 * len(COLUMNS) + 1)]
    for key, run in sorted(runs.items(), key=lambda item: -total(item[1])):
        digits = {c: 2 if c == "PSNR" else 3 for c in COLUMNS}
        cells = " | ".join(f"{run[s]['mean'][c]:.{digits[c]}f}" for c in COLUMNS for s in ("val40", "test64"))
        label = f"{key[0]}: {key[1]}" + ("" if run["steps"] == STEPS else f" ({run['steps']:,} steps)")
        label = f"**{label} (preset)**" if scores(run) in presets else label
        lines.append(f"| {label} | {cells} | {total(run):.3f} |")
    sums = [total(run) for run in runs.values() if scores(run) in presets]
    if sums:
        lines.append(
            f"\nPreset runs: sum of mIoU {min(sums):.3f} to {max(sums):.3f} (mean {sum(sums) / len(sums):.3f})."
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", action="append", default=[], help="FILE:RUN of a preset run (repeatable)")
    parser.add_argument("--also-steps", type=int, action="append", default=[], help="runs of this step count too")
    parser.add_argument("--out", type=Path, help="write the table here as well as printing it")
    args = parser.parse_args()
    presets = set()
    for named in args.preset:
        file, _, name = named.partition(":")
        run = json.loads((RESULTS / file).read_text())["runs"].get(name)
        if not isinstance(run, dict) or run.get("steps") != STEPS:
            raise SystemExit(f"rank_scratch.py: {RESULTS / file}: no 13,000-step run {name!r}")
        presets.add(scores(run))
    text = table(scratch_runs(steps=frozenset({STEPS, *args.also_steps})), presets)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
