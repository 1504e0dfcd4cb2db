"""Table 3 of ``affnerf eval grasp`` (conventions §6): {true mesh, mesh predicted from one image} × {whole
surface, the task's affordance only}, and the true mesh restricted to the task part its faces get from the
predicted field; every grasp scored on the true mesh at metric size."""

from __future__ import annotations

from typing import Any

import numpy as np

from affnerf.grasp.quality import CONE_EDGES, MU, TORSION

MESHES = ("true", "predicted")  #: where grasps are planned
#: Each condition is ``<mesh>_<surface>``: the whole surface, the task part of the mesh's own labels, and on the
#: true mesh also the task part of the labels the predicted field gives its faces (the effect of the predicted
#: affordance without the error of the predicted shape).
CONDITIONS = ("true_whole", "true_part", "true_predictedpart", "predicted_whole", "predicted_part")
LABELS = {
    "true_whole": "True mesh, whole surface",
    "true_part": "True mesh, true task part",
    "true_predictedpart": "True mesh, predicted task part",
    "predicted_whole": "Predicted from one image, whole surface",
    "predicted_part": "Predicted from one image, predicted task part",
}
#: The affordance a category is grasped by (the task part); `grasp` for any category not listed.
TASK_AFFORDANCE = {"cabinet": "pull"}
METRICS = ("epsilon", "epsilon_ratio", "on_part_share", "lift_success", "disturb_success")


def task_affordance(category: str) -> str:
    """The affordance ``category`` is grasped by.

    >>> task_affordance("cabinet"), task_affordance("screwdriver")
    ('pull', 'grasp')
    """
    return TASK_AFFORDANCE.get(category, "grasp")


def mesh_of(condition: str) -> str:
    """The mesh (:data:`MESHES`) a condition plans on.

    >>> mesh_of("true_predictedpart")
    'true'
    """
    return condition.split("_")[0]


def whole_of(condition: str) -> str:
    """The unrestricted condition on the same mesh.

    >>> whole_of("predicted_part"), whole_of("true_predictedpart")
    ('predicted_whole', 'true_whole')
    """
    return mesh_of(condition) + "_whole"


def same_mesh(condition: str) -> tuple[str, ...]:
    """Every condition planned on the mesh of ``condition``, whole surface first (a category counts in their
    means only where all of them have a value, so that the rows of a mesh stay comparable).

    >>> same_mesh("true_whole")
    ('true_whole', 'true_part', 'true_predictedpart')
    """
    return tuple(c for c in CONDITIONS if mesh_of(c) == mesh_of(condition))


def _mean(values: list) -> float | None:
    return float(np.mean(values)) if len(values) else None


def _ratio(value: float | None, whole: float | None) -> float | None:
    return None if value is None or not whole else value / whole


def _cell(rows: list[dict[str, Any]], cond: str) -> dict[str, Any]:
    """One category's numbers for one condition (epsilon 0 for an object without grasps)."""
    eps = [float(np.mean(o[cond]["epsilon"])) if o[cond]["epsilon"] else 0.0 for o in rows]
    return {
        "epsilon": _mean(eps),
        "on_part_share": _mean([x for o in rows for x in o[cond]["on_part"]]),
        "lift_success": _mean([x for o in rows for x in o[cond]["lift"]]),
        "disturb_success": _mean([x for o in rows for x in o[cond].get("disturb", [])]),
        "grasps": int(sum(o[cond]["grasps"] for o in rows)),
        "objects": len(rows),
        "no_grasp_objects": sum(1 for o in rows if not o[cond]["grasps"]),
    }


def summarise(objects: list[dict[str, Any]]) -> dict[str, Any]:
    """Per category and condition: mean epsilon, its ratio to the whole surface on the same mesh, the share of
    grasps with both contacts on the true task part, lift (and disturb) success, grasps, objects and objects
    without grasps; and the mean over categories (its ratio is the ratio of the mean epsilons).

    A share or success rate is undefined in a category where a condition has no grasp. So that the rows of a mesh
    stay comparable, their means cover the same categories: those where every row of the mesh is defined; the
    others are listed in ``mean[cond]["left_out"][metric]``.
    """
    out: dict[str, Any] = {"categories": {}, "mean": {}}
    cats = sorted({o["category"] for o in objects})
    for cat in cats:
        rows = [o for o in objects if o["category"] == cat]
        cells = {cond: _cell(rows, cond) for cond in CONDITIONS}
        for cond, cell in cells.items():
            cell["epsilon_ratio"] = _ratio(cell["epsilon"], cells[whole_of(cond)]["epsilon"])
        out["categories"][cat] = cells
    for cond in CONDITIONS:
        mean: dict[str, Any] = {"left_out": {}}
        for key in ("epsilon", "on_part_share", "lift_success", "disturb_success"):
            both = [c for c in cats if all(out["categories"][c][x][key] is not None for x in same_mesh(cond))]
            mean[key] = _mean([out["categories"][c][cond][key] for c in both])
            if len(both) < len(cats):
                mean["left_out"][key] = [c for c in cats if c not in both]
        mean["objects"] = sum(out["categories"][c][cond]["objects"] for c in cats)
        mean["no_grasp_objects"] = sum(out["categories"][c][cond]["no_grasp_objects"] for c in cats)
        out["mean"][cond] = mean
    for cond in CONDITIONS:
        out["mean"][cond]["epsilon_ratio"] = _ratio(
            out["mean"][cond]["epsilon"], out["mean"][whole_of(cond)]["epsilon"]
        )
    return out


def epsilon_convention() -> str:
    """The epsilon convention in words, for the table."""
    return (
        f"Ferrari-Canny epsilon on the L1 grasp wrench space; soft-finger contacts (torsion ±{TORSION * 1000:.1f} mm"
        f" × normal force), μ = {MU}, friction cones of {CONE_EDGES} edges, torques divided by the object radius"
        " (largest centroid-to-vertex distance); at the object's metric size, on the true mesh"
    )


_TITLES = {
    "epsilon": "Mean epsilon (mean over an object's grasps, 0 without grasps; mean over objects)",
    "epsilon_ratio": "Epsilon relative to the whole surface of the same mesh",
    "on_part_share": "Share of grasps with both contacts on the true task part (`grasp`; cabinet: `pull`)",
    "lift_success": "Physics lift success (best grasps per object)",
    "disturb_success": "Lift-and-disturb success: still held after turning ±90° about the closing axis and shaking",
}


def _fmt(key: str, value: float | None) -> str:
    if value is None:
        return "–"
    return f"{value:.4f}" if key == "epsilon" else (f"{value:.2f}" if key == "epsilon_ratio" else f"{100 * value:.0f}%")


def _left_out_note(summary: dict[str, Any], key: str) -> list[str]:
    """A line naming the categories a mesh's average leaves out for ``key`` (none: no line)."""
    notes = []
    for mesh in MESHES:
        mean = summary["mean"][f"{mesh}_whole"]
        left = mean.get("left_out", {}).get(key)
        if left and mean[key] is not None:  # not when no category has the metric (e.g. --no-disturb)
            notes.append(f"{mesh} mesh: {', '.join(left)}")
    if not notes:
        return []
    return [f"Averages leave out the categories where one row of the same mesh has no grasp ({'; '.join(notes)}).", ""]


_SHORT = {"on_part_share": "on the true task part", "lift_success": "lift", "disturb_success": "lift + disturb"}


def _points(value: float | None) -> str:
    return "–" if value is None else f"{100 * value:+.0f}"


def intervals_markdown(intervals: dict[str, Any]) -> list[str]:
    """Lines of a table of :func:`affnerf.eval.grasp_intervals.restriction_intervals`: each restricted row's
    difference from the whole surface of its mesh, in percentage points, with its interval."""
    keys = list(next(iter(intervals["rows"].values())))
    lines = [
        f"**Restricted minus whole surface of the same mesh** (percentage points; in brackets the"
        f" {100 * intervals['level']:.0f} % bootstrap interval over objects, resampled within each category,"
        f" {intervals['draws']} draws)",
        "",
        "| | " + " | ".join(_SHORT[k] for k in keys) + " |",
        "|" + " --- |" * (len(keys) + 1),
    ]
    for cond, cells in intervals["rows"].items():
        text = [f"{_points(c['difference'])} [{_points(c['low'])}, {_points(c['high'])}]" for c in cells.values()]
        lines.append(f"| {LABELS[cond]} | " + " | ".join(text) + " |")
    return [*lines, ""]


def table3_markdown(summary: dict[str, Any], context: dict[str, Any]) -> str:
    """Markdown of Table 3: one table per metric, rows = conditions, columns = categories and their average; then,
    when the summary has them, the restricted rows' differences with their intervals."""
    cats = sorted(summary["categories"])
    header = ["| | " + " | ".join(cats) + " | Average |", "|" + " --- |" * (len(cats) + 2)]
    lines = [f"# Grasps on {context.get('split', 'test')} objects: the true or predicted mesh, whole or task part", ""]
    lines += [f"Every grasp is scored on the true mesh. ε: {epsilon_convention()}.", ""]
    for key in METRICS:
        lines += [f"**{_TITLES[key]}**", "", *header]
        for cond in CONDITIONS:
            cells = [summary["categories"][c][cond][key] for c in cats] + [summary["mean"][cond][key]]
            lines.append(f"| {LABELS[cond]} | " + " | ".join(_fmt(key, v) for v in cells) + " |")
        lines += ["", *_left_out_note(summary, key)]
    if summary.get("intervals"):
        lines += intervals_markdown(summary["intervals"])
    lines += ["**Objects where planning found no grasp** (last column: all objects; `grasp_objects.json` says why)"]
    lines += ["", *header]
    for cond in CONDITIONS:
        cells = [summary["categories"][c][cond] for c in cats] + [summary["mean"][cond]]
        counts = [f"{cell.get('no_grasp_objects', 0)}/{cell.get('objects', 0)}" for cell in cells]
        lines.append(f"| {LABELS[cond]} | " + " | ".join(counts) + " |")
    lines.append("")
    objects = {c: summary["categories"][c]["true_whole"]["objects"] for c in cats}
    lines += [f"Objects per category: {objects}. Settings: `{context}`", ""]
    return "\n".join(lines)
