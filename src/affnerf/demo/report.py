"""The demo report: one self-contained HTML page (images next to it) with every example's input, turntable,
labelled mesh, grasps and numbers, and the model's metrics."""

from __future__ import annotations

import html
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from affnerf.vocab import AFFORDANCE_CLASSES, AFFORDANCE_PALETTE


@dataclass
class ExampleResult:
    """What the demo made for one example image (paths relative to the report's folder)."""

    name: str
    input_image: str
    prepared: str
    turntable: str
    mesh_preview: str
    grasps_picture: str | None
    model_file: str | None
    classes: dict[str, float]
    grasps: dict[str, Any] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)


_STYLE = """
body{font-family:system-ui,sans-serif;margin:24px;color:#222;max-width:1400px}
h1{margin-bottom:4px} .sub{color:#666;margin-top:0}
table{border-collapse:collapse;margin:8px 0 24px} td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}
th{background:#f3f3f3} td:first-child,th:first-child{text-align:left}
.example{border-top:1px solid #ddd;padding:16px 0;display:flex;flex-wrap:wrap;gap:16px;align-items:flex-start}
.example img{max-height:220px;border:1px solid #eee} .card{max-width:320px}
.swatch{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:middle;border:1px solid #555}
code{background:#f6f6f6;padding:1px 4px}
"""


def _swatch(name: str) -> str:
    cid = AFFORDANCE_CLASSES.index(name) if name in AFFORDANCE_CLASSES else 0
    r, g, b = (int(c) for c in AFFORDANCE_PALETTE[cid])
    return f'<span class="swatch" style="background:rgb({r},{g},{b})"></span>{html.escape(name)}'


def _metrics_table(metrics: dict[str, Any] | None) -> str:
    if not metrics or "categories" not in metrics:
        return "<p>No evaluation metrics were found for this model.</p>"
    keys = ("mIoU", "PA", "MPA", "PSNR")
    rows = [f"<tr><th>category</th>{''.join(f'<th>{k}</th>' for k in keys)}<th>objects</th></tr>"]
    items = list(metrics["categories"].items()) + [("mean", metrics["mean"])]
    for name, m in items:
        cells = "".join(f"<td>{m[k]:.3f}</td>" if isinstance(m.get(k), (int, float)) else "<td>–</td>" for k in keys)
        rows.append(f"<tr><td>{html.escape(name)}</td>{cells}<td>{m.get('objects', '')}</td></tr>")
    return "<table>" + "".join(rows) + "</table>"


def _example(ex: ExampleResult) -> str:
    classes = "<br>".join(f"{_swatch(c)}: {a * 1e4:.1f} cm²" for c, a in ex.classes.items()) or "no surface extracted"
    grasp = ""
    if ex.grasps:
        g = ex.grasps
        grasp = (
            f"<p><b>Grasps</b> ({html.escape(str(g.get('affordance')))}): {g.get('count', 0)} planned, "
            f"best ε {g.get('best_epsilon', 0):.4f}</p>"
        )
    timing = ", ".join(f"{k} {v:.1f} s" for k, v in ex.seconds.items())
    pictures = [
        ("input", ex.input_image),
        ("prepared crop", ex.prepared),
        ("turntable (RGB | affordance)", ex.turntable),
        ("affordance model", ex.mesh_preview),
    ] + ([("best grasps", ex.grasps_picture)] if ex.grasps_picture else [])
    figures = "".join(
        f'<figure><img src="{html.escape(src)}" alt="{html.escape(cap)}">'
        f"<figcaption>{html.escape(cap)}</figcaption></figure>"
        for cap, src in pictures
    )
    model = (
        f'<p>Mesh: <a href="{html.escape(ex.model_file)}">{html.escape(ex.model_file)}</a></p>' if ex.model_file else ""
    )
    return (
        f'<div class="example"><div class="card"><h3>{html.escape(ex.name)}</h3><p>{classes}</p>{grasp}{model}'
        f'<p class="sub">{timing}</p></div>{figures}</div>'
    )


def write_report(
    path: Path, examples: list[ExampleResult], model: str, metrics: dict[str, Any] | None, seconds: float
) -> Path:
    """Write the HTML report; image paths in ``examples`` are relative to its folder."""
    body = [
        "<h1>affnerf demo</h1>",
        f'<p class="sub">One image in, a 3D affordance model and grasps out. Model: <code>{html.escape(model)}</code>; '
        f"{len(examples)} examples in {seconds:.0f} s.</p>",
        "<h2>Model quality on held-out objects</h2>",
        _metrics_table(metrics),
        "<h2>Examples</h2>",
        *(_example(ex) for ex in examples),
        '<p class="sub">Open a folder in 3D with <code>affnerf view demo_out/&lt;example&gt;</code>.</p>',
    ]
    head = f"<head><meta charset='utf-8'><title>affnerf demo</title><style>{_STYLE}</style></head>"
    page = f"<!doctype html><html>{head}<body>{''.join(body)}</body></html>"
    Path(path).write_text(page)
    (Path(path).parent / "report.json").write_text(json.dumps([ex.__dict__ for ex in examples], indent=1))
    return Path(path)
