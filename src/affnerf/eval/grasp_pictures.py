"""Pictures of ``affnerf eval grasp``: per category, each condition's planning mesh coloured by affordance with
its best grasps, the true mesh's rows above the predicted mesh's."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from affnerf.eval.grasp_table import LABELS
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.io import render_grasps, save_png
from affnerf.grasp.planner import Grasp
from affnerf.grasp.target import GraspObject
from affnerf.pictures.compose import stack_rows, text_strip


def condition_panel(obj: GraspObject, grasps: list[Grasp], title: str, size: int = 200) -> np.ndarray:
    """(18 + size, 3 * size, 3) uint8: ``title`` above ``obj`` (metric, coloured by affordance) with its three
    best ``grasps`` from three sides; a blank panel saying so when ``obj`` has no surface."""
    if not len(obj.faces):
        return stack_rows([text_strip(f"{title}: no surface", 3 * size), np.full((size, 3 * size, 3), 255, np.uint8)])
    image = render_grasps(obj, grasps, ParallelJawGripper(), count=3, size=size)
    return stack_rows([text_strip(f"{title} ({len(grasps)} grasps)", image.shape[1]), image])


def write_category_picture(path: Path, panels: dict[str, tuple[GraspObject, list[Grasp]]], size: int = 200) -> None:
    """Write the panels of one object, conditions (keys of :data:`LABELS`) in table order, as a PNG."""
    rows = [condition_panel(obj, grasps, LABELS[cond], size) for cond, (obj, grasps) in panels.items()]
    save_png(path, stack_rows(rows))
