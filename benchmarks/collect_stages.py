"""Gather the scores of further stages run by side_by_side.sh's ``scored_stage`` into one results file.

For each NAME (a run W/NAME): its steps, the calibrated mesh level and optical depth (W/NAME/calibration.json),
val40 (W/val40_NAME/metrics.json: mean and per category), the surface errors (W/surface_errors_NAME.json, its
``affnerf`` summary), the validation grasps (W/grasp_NAME/grasp_metrics.json) and, where it was run, val40's
protocol on the 64 test objects (W/test64_NAME); a reference results file's runs
(``--reference``, e.g. the plain stage's row in points_weight.json) can be copied in beside them. With
``--markdown``, the tables of a results page (val40, per category, the hollow families and thin parts, grasps) are
written from those numbers, the shipped model's surface errors (results/surface_errors.json) as the first row of
theirs. With ``--compact`` the file leaves out the confusion matrices and per-class IoUs and rounds to 5 decimals.

``--stability NAME=SOURCE`` adds a run's view stability (``affnerf eval --stability-views``: the means of its
predictions, the spread over input views, overall and per category) and ``--fresh NAME=SOURCE`` its scores on the
192 fresh objects (``fresh_objects.sh``: mean and per category), as the run's ``stability`` and ``fresh192``. SOURCE
is the folder that command wrote (its metrics.json), or ``FILE.json#key.key`` for an entry of a committed results
file with the same fields (the shipped weights' scores, for instance). NAME must be one of the file's runs.

    .venv/bin/python benchmarks/collect_stages.py --work W --names a b --out benchmarks/results/X.json \
        [--reference benchmarks/results/points_weight.json:0.1:plain] [--markdown TABLES.md] \
        [--stability a=W/stab_a --stability shipped=benchmarks/results/X.json#stability.runs.shipped] \
        [--fresh a=W/fresh192_a --fresh shipped=benchmarks/results/validation_size.json#runs.shipped.fresh192]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def _read(path: Path) -> dict | None:
    """The JSON at ``path``, or None when it is not there (a stage not scored yet)."""
    return json.loads(path.read_text()) if path.exists() else None


def _eval_means(folder: Path) -> dict | None:
    """An ``affnerf eval`` folder's mean and per-category metrics, or None when it is not there."""
    metrics = _read(folder / "metrics.json")
    return None if metrics is None else {"mean": metrics["mean"], "categories": metrics["categories"]}


def compact(value):
    """``value`` without confusion matrices and per-class IoUs, floats rounded to 5 decimals (a results file's
    means and per-category metrics only)."""
    if isinstance(value, dict):
        return {k: compact(v) for k, v in value.items() if k not in ("confusion", "IoU_per_class")}
    if isinstance(value, list):
        return [compact(v) for v in value]
    return round(value, 5) if isinstance(value, float) else value


def stage_scores(work: Path, name: str) -> dict:
    """One stage's scores (see the module docstring); parts not yet written are None."""
    calibration = _read(work / name / "calibration.json") or {}
    summary = _read(work / name / "summary.json") or {}
    surface = _read(work / f"surface_errors_{name}.json")
    return {
        "steps": summary.get("step"),
        "level": calibration.get("chosen_level"),
        "optical_depth": calibration.get("chosen_optical_depth"),
        "val40": _eval_means(work / f"val40_{name}"),
        "surface_errors": None if surface is None else surface["summary"]["affnerf"],
        "grasp_val": _read(work / f"grasp_{name}" / "grasp_metrics.json"),
    }


def _committed_entry(source: str) -> dict:
    """The entry ``key.key`` of a results file named ``FILE.json#key.key``."""
    file, _, keys = source.partition("#")
    entry = json.loads(Path(file).read_text())
    for key in keys.split("."):
        if key not in entry:
            raise SystemExit(f"collect_stages.py: {file} has no entry {keys!r} (no key {key!r})")
        entry = entry[key]
    return entry


def _eval_folder(source: str, read) -> dict:
    """``read(folder)`` of the ``affnerf eval`` folder ``source``; a clear exit when its metrics.json is not there."""
    scores = read(Path(source))
    if scores is None:
        raise SystemExit(f"collect_stages.py: {source}/metrics.json is missing (the evaluation did not finish)")
    return scores


def _stability_means(folder: Path) -> dict | None:
    """An ``affnerf eval --stability-views`` folder's ``mean`` (the metrics over every input view's prediction),
    ``stability`` (mean mIoU and F@1cm spread over input views) and ``stability_categories`` (the same per
    category), or None when it is not there."""
    metrics = _read(folder / "metrics.json")
    if metrics is None:
        return None
    if "stability" not in metrics:
        raise SystemExit(f"collect_stages.py: {folder}/metrics.json has no stability (run with --stability-views)")
    stability = metrics["stability"]
    return {"mean": metrics["mean"], "stability": stability["mean"], "stability_categories": stability["categories"]}


def add_extra_scores(runs: dict, pairs: list[str], key: str, read) -> None:
    """Store a run's scores as ``runs[NAME][key]`` for each ``NAME=SOURCE`` of ``pairs``: ``read`` of the eval folder
    SOURCE, or the committed entry SOURCE = ``FILE.json#key.key``."""
    for pair in pairs:
        name, sep, source = pair.partition("=")
        if not sep or name not in runs:
            raise SystemExit(f"collect_stages.py: {pair!r} is not NAME=SOURCE with NAME one of {sorted(runs)}")
        runs[name][key] = _committed_entry(source) if "#" in source else _eval_folder(source, read)


def stability_table(runs: dict) -> str:
    """The view stability of every run scored there: the means over the predictions and the spreads."""
    scored = {name: r["stability"] for name, r in runs.items() if r.get("stability") is not None}
    rows = [
        [
            name,
            *(f"{s['mean'][k]:.3f}" for k in ("mIoU", "fscore_1cm")),
            *(f"{s['stability'][k]:.3f}" for k in ("mIoU_spread", "fscore_1cm_spread")),
            s["stability"]["objects"],
        ]
        for name, s in scored.items()
    ]
    head = ["stage", "mIoU", "F@1cm", "mIoU spread", "F@1cm spread", "objects"]
    return "View stability (each object from several input views; spread = max - min per object):\n\n" + _table(
        head, rows
    )


CATEGORIES = ("bottle", "bucket", "cabinet", "eyeglasses", "pen", "scissors", "screwdriver", "teapot")
#: (category, part) whose recall the thin-parts table shows: the bail, the cabinet handle, the eyeglass temple.
THIN_PARTS = (("bucket", "grasp", "bail"), ("cabinet", "pull", "handle"), ("eyeglasses", "wear", "temple"))
GRASP_CATEGORIES = ("bucket", "cabinet", "eyeglasses", "teapot")


def _row(cells: list) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _table(header: list[str], rows: list[list]) -> str:
    return "\n".join([_row(header), _row(["---"] * len(header)), *(_row(r) for r in rows)])


def eval_tables(runs: dict, key: str = "val40") -> str:
    """The means of the eval ``key`` (val40 or test64), and F@1cm / 3D affordance mIoU per category, one row per run
    scored there."""
    runs = {name: r for name, r in runs.items() if r.get(key) is not None}
    keys = ("mIoU", "MPA", "PSNR", "fscore_1cm", "affordance_miou_3d")
    means = [
        [name, f"{r['level']:g} /m, depth {r['optical_depth']:g}", *(f"{r[key]['mean'][k]:.3f}" for k in keys)]
        for name, r in runs.items()
    ]
    head = ["stage", "level (calibrated)", f"{key} mIoU", "MPA", "PSNR", "F@1cm", "3D aff. mIoU"]
    per_cat = [
        [
            name,
            *(
                f"{c['fscore_1cm']:.2f} / {c['affordance_miou_3d']:.2f}"
                for c in map(r[key]["categories"].get, CATEGORIES)
            ),
        ]
        for name, r in runs.items()
    ]
    return (
        _table(head, means)
        + f"\n\n{key}: F@1cm / 3D affordance mIoU per category:\n\n"
        + _table(["stage", *CATEGORIES], per_cat)
    )


def surface_table(runs: dict, shipped: dict) -> str:
    """F@1cm, cavity filled and thin-part recall of the hollow families on the test objects (surface_errors.py)."""
    head = ["stage", "bucket F", "bucket walls enclosed", "cabinet F", "cabinet cavity filled", "eyeglasses F"]
    head += [f"{label} recall" for _, _, label in THIN_PARTS]
    rows = []
    for name, s in [("shipped", shipped), *((n, r["surface_errors"]) for n, r in runs.items())]:
        if s is None:
            continue
        cells = [s["bucket"]["fscore"], s["bucket"]["solid"], s["cabinet"]["fscore"], s["cabinet"]["cavity_filled"]]
        cells += [s["eyeglasses"]["fscore"], *(s[c]["part_recall"][p] for c, p, _ in THIN_PARTS)]
        rows.append([name, *(f"{v:.2f}" for v in cells)])
    return _table(head, rows)


def grasp_table(runs: dict) -> str:
    """Grasps restricted to the predicted task part on validation objects: on-part share and lift-and-disturb."""

    def cell(v: dict) -> str:
        if not v["grasps"]:
            return f"no grasp ({v['no_grasp_objects']}/{v['objects']} without)"
        return (
            f"{v['on_part_share']:.0%} on part, {v['disturb_success']:.0%} lift+disturb "
            f"({v['no_grasp_objects']}/{v['objects']} without)"
        )

    rows = []
    for name, r in runs.items():
        if r["grasp_val"] is None:  # not grasped yet
            continue
        cats = r["grasp_val"]["categories"]
        mean = r["grasp_val"]["mean"]["predicted_part"]
        rows.append(
            [
                name,
                *(cell(cats[c]["predicted_part"]) for c in GRASP_CATEGORIES),
                f"{mean['on_part_share']:.0%} on part, {mean['disturb_success']:.0%} lift+disturb",
            ]
        )
    return _table(["stage", *GRASP_CATEGORIES, "mean over the categories with grasps"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--names", nargs="+", required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--reference", action="append", default=[], help="FILE:RUN:NAME, a run of a results file")
    parser.add_argument("--markdown", type=Path, help="write the results page's tables here")
    parser.add_argument("--compact", action="store_true", help="no confusion matrices or per-class IoUs")
    parser.add_argument("--stability", action="append", default=[], help="NAME=FOLDER or NAME=FILE.json#key.key")
    parser.add_argument("--fresh", action="append", default=[], help="NAME=FOLDER or NAME=FILE.json#key.key")
    args = parser.parse_args()
    runs = {}
    for ref in args.reference:
        file, run, name = ref.rsplit(":", 2)
        runs[name] = json.loads(Path(file).read_text())["runs"][run]
    runs.update({name: stage_scores(args.work, name) for name in args.names})
    for name, run in runs.items():  # val40's protocol on the 64 test objects, where it was run (a reference's own)
        run["test64"] = _eval_means(args.work / f"test64_{name}") or run.get("test64")
    add_extra_scores(runs, args.stability, "stability", _stability_means)
    add_extra_scores(runs, args.fresh, "fresh192", _eval_means)
    args.out.write_text(json.dumps({"runs": compact(runs) if args.compact else runs}, indent=1) + "\n")
    if args.markdown:
        shipped = json.loads((Path(__file__).parent / "results" / "surface_errors.json").read_text())
        parts = [eval_tables(runs), surface_table(runs, shipped["summary"]["affnerf"]), grasp_table(runs)]
        if any(r.get("test64") for r in runs.values()):
            parts.append(eval_tables(runs, "test64"))
        if any(r.get("fresh192") for r in runs.values()):
            parts.append(eval_tables(runs, "fresh192"))
        if any(r.get("stability") for r in runs.values()):
            parts.append(stability_table(runs))
        args.markdown.write_text("\n\n".join(parts) + "\n")


if __name__ == "__main__":
    main()
