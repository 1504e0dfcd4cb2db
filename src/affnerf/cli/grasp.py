"""``affnerf grasp``: plan parallel-jaw grasps on a labelled mesh, or score given grasps."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Literal

from tyro.extras import SubcommandApp

app = SubcommandApp()


@app.command(name="plan", is_default=True)
def plan(
    mesh: Path,
    out: Path,
    affordance: str = "none",
    num: int = 64,
    gripper: Literal["parallel"] = "parallel",
    candidates: int = 64,
    refine_steps: int = 40,
    seed: int = 0,
) -> None:
    """Plan parallel-jaw grasps on a mesh (PLY; with --affordance, one carrying an integer `affordance` property).

    Antipodal candidate pairs are sampled on the surface (on the wanted affordance only, when given), refined all
    at once by a gradient-based local search, closed on the mesh, checked for gripper collisions and ranked by the
    Ferrari-Canny epsilon. Writes OUT/grasps.json, OUT/grasps.glb (mesh and gripper models) and OUT/grasps.png.

    Args:
        mesh: the mesh (a dataset's mesh.ply or a predicted affordance_model.ply).
        out: output folder.
        affordance: restrict contacts to this affordance (e.g. grasp), or none.
        num: grasps kept, best first.
        gripper: the gripper model (parallel jaw: 0.08 m opening, 0.02 m pads).
        candidates: antipodal pairs sampled (each tried with four approach directions).
        refine_steps: local-search steps (0 = none).
        seed: random seed.
    """
    from dataclasses import replace

    from affnerf.grasp.gripper import ParallelJawGripper
    from affnerf.grasp.io import export_scene, render_grasps, save_png, summary, write_grasps
    from affnerf.grasp.planner import PlanConfig, plan_grasps
    from affnerf.grasp.target import load_grasp_object

    obj = load_grasp_object(mesh, need_affordance=affordance != "none")
    config = PlanConfig(affordance=affordance, num=num, candidates=candidates, seed=seed)
    config = replace(config, refine=replace(config.refine, steps=refine_steps))
    hand = ParallelJawGripper()
    grasps = plan_grasps(obj, config, hand)
    out.mkdir(parents=True, exist_ok=True)
    write_grasps(out / "grasps.json", grasps, str(mesh), affordance, hand)
    export_scene(out / "grasps.glb", obj, grasps, hand)
    save_png(out / "grasps.png", render_grasps(obj, grasps, hand))
    print(json.dumps(summary(grasps)))
    print(f"-> {out / 'grasps.json'}")


@app.command(name="score")
def score(mesh: Path, grasps: Path, out: Path | None = None) -> None:
    """Score grasps on a mesh: close the jaws on it, then the Ferrari-Canny epsilon and the affordance at each
    contact.

    Args:
        mesh: the mesh to score on (e.g. the ground-truth mesh.ply).
        grasps: a grasps.json file.
        out: also write the scores as JSON here.
    """
    import numpy as np

    from affnerf.fileio import write_json_atomic
    from affnerf.grasp.io import read_grasps
    from affnerf.grasp.scoring import score_grasps
    from affnerf.grasp.target import load_grasp_object

    obj = load_grasp_object(mesh)
    poses = np.array([p for p, _ in read_grasps(grasps)]).reshape(-1, 4, 4)
    scores = score_grasps(obj, poses)
    print(f"{'#':>3} {'epsilon':>9} {'width':>7}  affordance at contacts")
    for i, s in enumerate(scores):
        print(f"{i:>3} {s.epsilon:>9.5f} {s.width:>7.4f}  {' / '.join(s.affordance)}")
    if out is not None:
        write_json_atomic(out, {"mesh": str(mesh), "grasps": str(grasps), "scores": [s.to_json() for s in scores]})
        print(f"-> {out}")
