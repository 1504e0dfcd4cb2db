"""Table 3 of ``affnerf eval grasp`` as a 2×2 (conventions §6): {true mesh, mesh predicted from one image} ×
{whole surface, the task's affordance only}, every grasp scored on the true mesh at metric size."""

from __future__ import annotations

from typing import Any

import numpy as np

from affnerf.grasp.quality import CONE_EDGES, MU, TORSION

MESHES = ("true", "predicted")  #: where grasps are planned
SURFACES = ("whole", "part")  #: on the whole surface, or on the task's affordance only
CONDITIONS = tuple(f"{m}_{s}" for m in MESHES for s in SURFACES)
LABELS = {
    "true_whole": "True mesh, whole surface",
    "true_part": "True mesh, task part only",
    "predicted_whole": "Predicted from one image, whole surface",
    "predicted_part": "Predicted from one image, task part only",
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


def whole_of(condition: str) -> str:
    """The unrestricted condition on the same mesh.

    >>> whole_of("predicted_part")
    'predicted_whole'
    """
    return condition.split("_")[0] + "_whole"


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
    }


def summarise(objects: list[dict[str, Any]]) -> dict[str, Any]:
    """Per category and condition: mean epsilon, its ratio to the whole surface on the same mesh, the share of
    grasps with both contacts on the true task part, lift (and disturb) success, grasps and objects; and the mean
    over categories (its ratio is the ratio of the mean epsilons)."""
    out: dict[str, Any] = {"categories": {}, "mean": {}}
    cats = sorted({o["category"] for o in objects})
    for cat in cats:
        rows = [o for o in objects if o["category"] == cat]
        cells = {cond: _cell(rows, cond) for cond in CONDITIONS}
        for cond, cell in cells.items():
            cell["epsilon_ratio"] = _ratio(cell["epsilon"], cells[whole_of(cond)]["epsilon"])
        out["categories"][cat] = cells
    for cond in CONDITIONS:
        mean = {}
        for key in ("epsilon", "on_part_share", "lift_success", "disturb_success"):
            vals = [out["categories"][c][cond][key] for c in cats if out["categories"][c][cond][key] is not None]
            mean[key] = _mean(vals)
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


def table3_markdown(summary: dict[str, Any], context: dict[str, Any]) -> str:
    """Markdown of the 2×2: one table per metric, rows = conditions, columns = categories and their average."""
    cats = sorted(summary["categories"])
    lines = [f"# Grasps on {context.get('split', 'test')} objects: true or predicted mesh × whole surface or part", ""]
    lines += [f"Every grasp is scored on the true mesh. ε: {epsilon_convention()}.", ""]
    for key in METRICS:
        lines += [
            f"**{_TITLES[key]}**",
            "",
            "| | " + " | ".join(cats) + " | Average |",
            "|" + " --- |" * (len(cats) + 2),
        ]
        for cond in CONDITIONS:
            cells = [summary["categories"][c][cond][key] for c in cats] + [summary["mean"][cond][key]]
            lines.append(f"| {LABELS[cond]} | " + " | ".join(_fmt(key, v) for v in cells) + " |")
        lines.append("")
    objects = {c: summary["categories"][c]["true_whole"]["objects"] for c in cats}
    lines += [f"Objects per category: {objects}. Settings: `{context}`", ""]
    return "\n".join(lines)
