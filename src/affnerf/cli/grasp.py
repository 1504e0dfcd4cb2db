"""``affnerf grasp``: plan parallel-jaw grasps on a labelled mesh, or score given grasps, at the object's metric
size (conventions §6)."""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from tyro.extras import SubcommandApp

if TYPE_CHECKING:
    from affnerf.grasp.io import PlannedGrasps

app = SubcommandApp()


@app.command(name="plan", is_default=True)
def plan(
    mesh: Path,
    out: Path,
    affordance: str = "none",
    num: int = 64,
    gripper: Literal["parallel"] = "parallel",
    max_opening: float = 0.08,
    object_size: float | None = None,
    category: str | None = None,
    candidates: int = 64,
    refine_steps: int = 40,
    seed: int = 0,
    part_margin: float | None = None,
    width_clearance: float | None = None,
    min_confidence: float | None = None,
    rank: Literal["epsilon", "hold"] | None = None,
) -> None:
    """Plan parallel-jaw grasps on a mesh (PLY; with --affordance, one carrying an integer `affordance` property).

    The mesh is first brought to its metric size: --object-size, else the `scale` of a transforms.json beside it
    (a dataset mesh), else the typical size of --category, else it is taken as metres. Antipodal candidate pairs
    are sampled on the surface (on the wanted affordance only, when given), refined all at once by a
    gradient-based local search, closed on the mesh, checked for gripper collisions and ranked by the
    Ferrari-Canny epsilon (--rank hold: by the weight they carry while turned). Writes OUT/grasps.json (metric
    object frame, size used; for a fitted prediction also the photo's camera frame, conventions §6),
    OUT/grasps.glb and OUT/grasps.png. No grasp: stderr says why.

    Args:
        mesh: the mesh (a dataset's mesh.ply or a predicted affordance_model.ply).
        out: output folder.
        affordance: restrict contacts to this affordance (e.g. grasp), or none.
        num: grasps kept, best first.
        gripper: the gripper model (parallel jaw: 0.02 m pads).
        max_opening: the gripper's widest opening, metres.
        object_size: the object's largest side in metres (overrides transforms.json and --category).
        category: the object's category, for its typical size (conventions §6) when no size is known.
        candidates: antipodal pairs sampled (each tried with four approach directions).
        refine_steps: local-search steps (0 = none).
        seed: random seed.
        part_margin: with --affordance, contacts keep this distance (m) from other labels, where a prediction's
            labels are least sure (default: grasp.planner.PART_MARGIN, 0.01; 0 = the whole part; conventions §6).
        width_clearance: grasps stay this far (m) below --max-opening (default: 0.012 on a mesh `affnerf predict`
            wrote, whose widths are uncertain, i.e. with a prediction.json beside it; else 0; conventions §6).
        min_confidence: with --affordance, on a mesh whose faces carry `confidence` (a predicted one), contacts are
            first sought on the part's faces at least this sure of their label, then on the whole part (default:
            0, off: on validation objects 0.7-0.9 cost lift-and-disturb; conventions §6).
        rank: order by epsilon (Ferrari-Canny) or hold (weight carried through ±90° turns; conventions §6).
    """
    from affnerf.grasp.gripper import ParallelJawGripper
    from affnerf.grasp.io import default_clearance, plan_into
    from affnerf.grasp.planner import PlanConfig, RefineConfig
    from affnerf.grasp.target import load_grasp_object

    canonical = load_grasp_object(mesh, need_affordance=affordance != "none")
    config = PlanConfig(affordance, num, candidates, seed=seed, refine=RefineConfig(steps=refine_steps))
    given = {"part_margin": part_margin, "min_confidence": min_confidence, "rank": rank}  # None: the default
    given["width_clearance"] = default_clearance(mesh) if width_clearance is None else width_clearance
    config = replace(config, **{k: v for k, v in given.items() if v is not None})
    gripper = ParallelJawGripper(max_opening=max_opening)
    report_planned(plan_into(out, canonical, mesh, config, gripper, object_size, category), out)


def report_planned(planned: PlannedGrasps, out: Path) -> None:
    """Say what `grasp plan` did: the size planned at and why there is no grasp (stderr), the grasps' summary and
    where they are (stdout)."""
    from affnerf.grasp.explain import no_grasp_text
    from affnerf.grasp.io import summary
    from affnerf.grasp.size import extent

    size = f"{extent(planned.obj.vertices):.3f} m ({planned.size.source})"
    print(f"size: largest side {size}; poses in metres", file=sys.stderr)
    if planned.no_grasp is not None:
        print(no_grasp_text(planned.no_grasp), file=sys.stderr)
    print(json.dumps(summary(planned.grasps)))
    print(f"-> {out / 'grasps.json'}")


@app.command(name="score")
def score(
    mesh: Path,
    grasps: Path,
    out: Path | None = None,
    object_size: float | None = None,
    category: str | None = None,
) -> None:
    """Score grasps on a mesh at its metric size: close the jaws on it, then the Ferrari-Canny epsilon and the
    affordance at each contact.

    The mesh's size is found as in `affnerf grasp plan`, falling back to the grasps file's `size.scale`. The
    grasps are read in their file's metric frame and moved to the scored mesh's.

    Args:
        mesh: the mesh to score on (e.g. the ground-truth mesh.ply).
        grasps: a grasps.json file.
        out: also write the scores as JSON here.
        object_size: the object's largest side in metres.
        category: the object's category, for its typical size when no size is known.
    """
    import numpy as np

    from affnerf.fileio import write_json_atomic
    from affnerf.grasp.io import read_grasp_scale, read_grasps
    from affnerf.grasp.scoring import score_grasps
    from affnerf.grasp.size import ObjectSize, rescale_poses, resolve_size, scaled
    from affnerf.grasp.target import load_grasp_object

    canonical = load_grasp_object(mesh)
    file_scale = read_grasp_scale(grasps)
    size = resolve_size(mesh, canonical.vertices, object_size, category)
    if size.source == "mesh as given" and file_scale is not None:
        size = ObjectSize(1.0 / file_scale, "grasps.json scale")
    poses = np.array([p for p, _ in read_grasps(grasps)]).reshape(-1, 4, 4)
    poses = rescale_poses(poses, (file_scale or 1.0) * size.factor)  # file frame -> canonical -> this metric
    scores = score_grasps(scaled(canonical, size.factor), poses)
    print(f"size: scale {size.scale:.4g} ({size.source})")
    print(f"{'#':>3} {'epsilon':>9} {'width':>7}  affordance at contacts")
    for i, s in enumerate(scores):
        print(f"{i:>3} {s.epsilon:>9.5f} {s.width:>7.4f}  {' / '.join(s.affordance)}")
    if out is not None:
        result = {"mesh": str(mesh), "grasps": str(grasps), "scale": size.scale, "size_source": size.source}
        write_json_atomic(out, {**result, "scores": [s.to_json() for s in scores]})
        print(f"-> {out}")
