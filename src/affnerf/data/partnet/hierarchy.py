"""The part hierarchy (``result.json``) and the category (``meta.json``) of a PartNet-Mobility object.

``result.json`` is a list of trees of nodes ``{"id", "name", "text", "children" | "objs"}``; a leaf (a node
without children) lists the OBJ files (names without ``.obj``) that make it up.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from affnerf.errors import input_error
from affnerf.fileio import read_json_file


@dataclass(frozen=True)
class Leaf:
    """A leaf of the part hierarchy.

    Attributes:
        id: the node id (unique within the object).
        name: the node name (e.g. ``handle``), lower case.
        objs: the OBJ file stems of its geometry (e.g. ``("original-52",)``).
        ancestors: its ancestors' names, nearest first (e.g. ``("cabinet_door", "cabinet", "storage_furniture")``).
    """

    id: int
    name: str
    objs: tuple[str, ...]
    ancestors: tuple[str, ...]


def _node_name(node: dict[str, Any]) -> str:
    name = node.get("name") or node.get("text") or ""
    return "_".join(str(name).lower().split())


def leaves_of(nodes: Any, path: Path) -> list[Leaf]:
    """The leaves of a parsed ``result.json``, in depth-first file order.

    Args:
        nodes: the parsed JSON (a list of root nodes, or one root node).
        path: the file, for messages.

    Raises:
        AffnerfError: a node that is not an object, lacks an integer ``id``, or whose ``children``/``objs``
            are not lists.

    Example:
        >>> tree = [{"id": 0, "name": "bottle", "children": [{"id": 7, "name": "lid", "objs": ["original-2"]}]}]
        >>> leaves_of(tree, Path("result.json"))
        [Leaf(id=7, name='lid', objs=('original-2',), ancestors=('bottle',))]
    """
    out: list[Leaf] = []

    def visit(node: Any, ancestors: tuple[str, ...]) -> None:
        if not isinstance(node, dict) or isinstance(node.get("id"), bool) or not isinstance(node.get("id"), int):
            raise input_error(path, f"malformed node {str(node)[:60]!r} (needs an object with an integer 'id')")
        children = node.get("children") or []
        objs = node.get("objs") or []
        if not isinstance(children, list) or not isinstance(objs, list):
            raise input_error(path, f"node {node['id']}: 'children' and 'objs' must be lists")
        name = _node_name(node)
        if children:
            for child in children:
                visit(child, (name, *ancestors))
        else:
            out.append(Leaf(id=node["id"], name=name, objs=tuple(str(o) for o in objs), ancestors=ancestors))

    for root in nodes if isinstance(nodes, list) else [nodes]:
        visit(root, ())
    return out


def read_leaves(path: Path) -> list[Leaf]:
    """The leaves of a ``result.json`` file (see :func:`leaves_of`)."""
    return leaves_of(read_json_file(path), Path(path))


def read_model_cat(path: Path) -> str:
    """The ``model_cat`` of a ``meta.json`` file (e.g. ``StorageFurniture``).

    Raises:
        AffnerfError: a missing or invalid file, or no ``model_cat`` string in it.
    """
    meta = read_json_file(path)
    cat = meta.get("model_cat") if isinstance(meta, dict) else None
    if not isinstance(cat, str) or not cat.strip():
        raise input_error(path, "no 'model_cat' string")
    return cat.strip()
