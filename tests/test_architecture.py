"""The package's layers (docs/architecture.md): every import points down the pipeline, never up, and no two
subpackages import each other. Lazy imports inside functions count too."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "affnerf"

#: Lowest first; a module may import from its own layer or a lower one. Same as the table in docs/architecture.md.
LAYERS = [
    {"errors", "vocab", "fileio", "meshio", "solid", "environment"},
    {"objects"},
    {"data"},
    {"rendering", "metrics", "pictures"},
    {"model"},
    {"train"},
    {"predict"},
    {"grasp"},
    {"eval"},
    {"viewer", "demo", "bench"},
    {"cli"},
]
LAYER = {name: rank for rank, names in enumerate(LAYERS) for name in names}


def _unit(module: str) -> str:
    """``affnerf.data.partnet.urdf`` -> ``data``; ``affnerf.vocab`` -> ``vocab``."""
    return module.split(".")[1]


def _imports(path: Path) -> set[str]:
    """Every ``affnerf.*`` module a file imports (relative imports resolved), anywhere in the file."""
    module = "affnerf." + ".".join(path.relative_to(SRC).with_suffix("").parts)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("affnerf.")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                found.add(".".join(base + ([node.module] if node.module else [])))
            elif node.module and node.module.startswith("affnerf."):
                found.add(node.module)
    return {m for m in found if m.count(".") >= 1}


def _edges() -> dict[str, set[str]]:
    edges: dict[str, set[str]] = defaultdict(set)
    for path in SRC.rglob("*.py"):
        here = _unit("affnerf." + ".".join(path.relative_to(SRC).with_suffix("").parts))
        if here == "__init__":  # the package root imports nothing of its own
            continue
        edges[here] |= {_unit(m) for m in _imports(path)} - {here}
    return edges


def test_every_unit_has_a_layer():
    units = {p.stem if p.is_file() else p.name for p in SRC.iterdir() if not p.name.startswith("_")}
    units = {u for u in units if (SRC / u).is_dir() or (SRC / f"{u}.py").is_file()} - {"py"}
    assert units <= set(LAYER) | {"weights"}, f"give these a layer: {sorted(units - set(LAYER) - {'weights'})}"


def test_imports_point_down_the_pipeline():
    upward = [f"{a} -> {b}" for a, targets in _edges().items() for b in targets if LAYER[b] > LAYER[a]]
    assert not upward, f"imports from a higher layer: {upward}"


def test_no_two_units_import_each_other():
    edges = _edges()
    mutual = sorted({tuple(sorted((a, b))) for a, targets in edges.items() for b in targets if a in edges.get(b, ())})
    assert not mutual, f"units that import each other: {mutual}"
