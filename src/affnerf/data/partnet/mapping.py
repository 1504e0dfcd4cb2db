"""The category-aware table from PartNet-Mobility names to affnerf categories and affordances (conventions §3).

The table ships as ``mapping.yaml`` beside this module (its header documents the schema); a user's YAML file with
the same schema is merged over it. A leaf takes the affordance of its own name, else of its ancestors' names
nearest first, else the category default (a warning naming the part, or an error with ``strict``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from affnerf.data.partnet.hierarchy import Leaf
from affnerf.errors import input_error
from affnerf.vocab import AFFORDANCE_CLASSES

logger = logging.getLogger(__name__)

#: The file name of the shipped table inside this package.
MAPPING_FILE = "mapping.yaml"

_KEYS = ("category", "default", "parts", "yaw_deg")


@dataclass(frozen=True)
class CategoryMapping:
    """How one PartNet-Mobility ``model_cat`` maps to affnerf.

    Attributes:
        model_cat: the PartNet-Mobility category (e.g. ``StorageFurniture``).
        category: the affnerf category (e.g. ``cabinet``).
        default: the affordance of leaves no name in ``parts`` matches.
        parts: node name (lower case) -> affordance.
        yaw_deg: rotation about +z (degrees) that turns the category's PartNet-Mobility front into the
            procedural family's canonical front (conventions §1), e.g. 90 for cabinets, whose fronts face -x after the
            URDF's base joint but -y in affnerf.
    """

    model_cat: str
    category: str
    default: str
    parts: dict[str, str] = field(default_factory=dict)
    yaw_deg: float = 0.0


def _check_affordance(name: Any, path: Path | str, where: str) -> str:
    if not isinstance(name, str) or name not in AFFORDANCE_CLASSES[1:]:
        known = ", ".join(AFFORDANCE_CLASSES[1:])
        raise input_error(path, f"{where}: unknown affordance {name!r} (known: {known})")
    return name


def parse_mapping(data: Any, path: Path | str, partial: bool = False) -> dict[str, dict[str, Any]]:
    """Validate the parsed YAML of a mapping file.

    Args:
        data: the parsed YAML: ``{model_cat: {"category", "default", "parts"}}``.
        path: the file, for messages.
        partial: allow entries without ``category``/``default`` (a user file extending a shipped entry).

    Returns:
        ``{model_cat: {key: value}}`` with only the keys present, ``parts`` keys lower case.

    Raises:
        AffnerfError: naming ``path``, for a wrong structure, an unknown key or an affordance outside the
            vocabulary.
    """
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise input_error(path, "a mapping file is a YAML mapping of PartNet model_cat -> entry")
    out: dict[str, dict[str, Any]] = {}
    for cat, entry in data.items():
        where = f"entry {cat!r}"
        if not isinstance(entry, dict):
            raise input_error(path, f"{where}: expected a mapping with keys {', '.join(_KEYS)}")
        unknown = sorted(set(map(str, entry)) - set(_KEYS))
        if unknown:
            raise input_error(path, f"{where}: unknown keys {unknown} (known: {', '.join(_KEYS)})")
        checked: dict[str, Any] = {}
        if "category" in entry:
            if not isinstance(entry["category"], str) or not entry["category"]:
                raise input_error(path, f"{where}: 'category' must be a name")
            checked["category"] = entry["category"]
        if "default" in entry:
            checked["default"] = _check_affordance(entry["default"], path, f"{where} default")
        if "yaw_deg" in entry:
            yaw = entry["yaw_deg"]
            if not isinstance(yaw, (int, float)) or isinstance(yaw, bool):
                raise input_error(path, f"{where}: 'yaw_deg' must be a number of degrees")
            checked["yaw_deg"] = float(yaw)
        parts = entry.get("parts") or {}
        if not isinstance(parts, dict):
            raise input_error(path, f"{where}: 'parts' must map node names to affordances")
        checked["parts"] = {str(k).lower(): _check_affordance(v, path, f"{where} part {k!r}") for k, v in parts.items()}
        if not partial and ("category" not in checked or "default" not in checked):
            raise input_error(path, f"{where}: needs 'category' and 'default'")
        out[str(cat)] = checked
    return out


def _read_yaml(text: str, path: Path | str) -> Any:
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise input_error(path, f"not a valid YAML file ({' '.join(str(exc).split())})") from None


def load_mapping(user: Path | None = None) -> dict[str, CategoryMapping]:
    """The shipped table, with a user's mapping file merged over it.

    Args:
        user: a YAML file with the shipped schema, or ``None``. Its ``category``/``default`` replace the
            shipped ones; its ``parts`` entries add to or replace the shipped ones. A ``model_cat`` new to the
            table needs both ``category`` and ``default``.

    Returns:
        ``{model_cat: CategoryMapping}``.

    Raises:
        AffnerfError: naming the user file, when it is missing, not YAML, or malformed (see
            :func:`parse_mapping`).
    """
    text = resources.files("affnerf.data.partnet").joinpath(MAPPING_FILE).read_text(encoding="utf-8")
    shipped = parse_mapping(_read_yaml(text, MAPPING_FILE), MAPPING_FILE)
    table = {
        cat: CategoryMapping(cat, e["category"], e["default"], dict(e["parts"]), e.get("yaw_deg", 0.0))
        for cat, e in shipped.items()
    }
    if user is None:
        return table
    user = Path(user)
    if not user.is_file():
        raise input_error(user, "mapping file not found")
    for cat, e in parse_mapping(_read_yaml(user.read_text(encoding="utf-8"), user), user, partial=True).items():
        base = table.get(cat)
        if base is None:
            if "category" not in e or "default" not in e:
                raise input_error(user, f"entry {cat!r}: a model_cat new to the table needs 'category' and 'default'")
            table[cat] = CategoryMapping(cat, e["category"], e["default"], dict(e["parts"]), e.get("yaw_deg", 0.0))
        else:
            table[cat] = replace(
                base,
                category=e.get("category", base.category),
                default=e.get("default", base.default),
                parts={**base.parts, **e["parts"]},
                yaw_deg=e.get("yaw_deg", base.yaw_deg),
            )
    return table


def category_mapping(table: dict[str, CategoryMapping], model_cat: str, meta_path: Path) -> CategoryMapping:
    """The entry of ``model_cat``.

    Raises:
        AffnerfError: naming ``meta_path`` when the table has no such category, and how to give one (``--mapping
            FILE``; ``affnerf data import-partnet --help`` shows a minimal file).
    """
    try:
        return table[model_cat]
    except KeyError:
        known = ", ".join(sorted(table))
        raise input_error(
            meta_path,
            f"model_cat {model_cat!r} has no mapping (known: {known}); give one with --mapping FILE "
            f"(a minimal file is shown by 'affnerf data import-partnet --help')",
        ) from None


def leaf_affordance(
    leaf: Leaf,
    entry: CategoryMapping,
    result_path: Path,
    part_name: str | None = None,
    strict: bool = False,
) -> str:
    """The affordance of a hierarchy leaf: its own name, then its ancestors' nearest first, then the default.

    Args:
        leaf: the leaf.
        entry: the object's category mapping.
        result_path: the ``result.json`` file, for messages.
        part_name: the part's name in the asset, for messages (default: the leaf name).
        strict: make a leaf no name matches an error instead of a warning.

    Raises:
        AffnerfError: with ``strict``, naming ``result_path`` and the part.

    Example:
        >>> e = CategoryMapping("StorageFurniture", "cabinet", "support", {"cabinet_frame": "support"})
        >>> leaf_affordance(Leaf(39, "other_leaf", (), ("other", "cabinet_frame")), e, Path("result.json"))
        'support'
    """
    for name in (leaf.name, *leaf.ancestors):
        if name in entry.parts:
            return entry.parts[name]
    label = part_name or leaf.name
    problem = (
        f"part {label!r} (leaf {leaf.id}, path {'/'.join(reversed((leaf.name, *leaf.ancestors)))}) has no "
        f"affordance in the {entry.model_cat} mapping"
    )
    if strict:
        raise input_error(result_path, problem)
    logger.warning("%s: %s; using the default %r", result_path, problem, entry.default)
    return entry.default
