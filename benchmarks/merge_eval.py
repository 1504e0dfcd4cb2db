"""Merge `affnerf eval` folders of disjoint categories (run side by side, one per core) into one folder, as one
evaluation of every category would have written it: ``metrics_<method>.json``, ``metrics.json``, ``table2.md``,
the example pictures and ``figure.png``.

    .venv/bin/python benchmarks/merge_eval.py --parts EVAL_A EVAL_B --out EVAL
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

from PIL import Image

from affnerf.eval.protocol import merge_metrics
from affnerf.eval.report import figure_grid, read_method_results, table2_markdown
from affnerf.fileio import write_json_atomic


def merge_folders(parts: list[Path], out: Path) -> list[str]:
    """Write the merged folder; returns the methods merged (every part must hold the same ones)."""
    methods = [sorted(r["method"] for r in read_method_results(p)) for p in parts]
    if any(m != methods[0] for m in methods):
        raise SystemExit(f"merge_eval: the parts hold different methods: {methods}")
    out.mkdir(parents=True, exist_ok=True)
    for method in methods[0]:
        merged = merge_metrics([json.loads((p / f"metrics_{method}.json").read_text()) for p in parts])
        write_json_atomic(out / f"metrics_{method}.json", merged)
    for part in parts:
        if (part / "examples").is_dir():
            shutil.copytree(part / "examples", out / "examples", dirs_exist_ok=True)
    everything = read_method_results(out)
    write_json_atomic(out / "metrics.json", everything[0])
    (out / "table2.md").write_text(table2_markdown(everything))
    figure = figure_grid(out, [r["method"] for r in everything])
    if figure is not None:
        Image.fromarray(figure).save(out / "figure.png")
    return methods[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, nargs="+", required=True)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    print("merged", ", ".join(merge_folders(args.parts, args.out)), "->", args.out)


if __name__ == "__main__":
    main()
