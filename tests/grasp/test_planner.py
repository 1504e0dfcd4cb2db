"""Planning grasps: affordance restriction, collision-free results, the local search, the CLI and its errors."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import torch
import trimesh

from affnerf.cli.main import main
from affnerf.grasp.gripper import ParallelJawGripper, grasp_pose
from affnerf.grasp.planner import (
    PlanConfig,
    collides,
    part_masks,
    plan_grasps,
    sample_antipodal,
    shrink_part,
    trusted_part,
)
from affnerf.grasp.refine import RefineConfig, grasp_energy, refine_grasps
from affnerf.grasp.target import GraspObject
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.objects.asset import merge_parts
from affnerf.objects.registry import make_object, object_seed
from affnerf.vocab import AFFORDANCE_CLASSES


@pytest.fixture(scope="module")
def screwdriver() -> GraspObject:
    surface = merge_parts(make_object("screwdriver", object_seed(0, "screwdriver", 2)))
    return GraspObject(surface.vertices, surface.faces, surface.face_affordance.astype(np.int64), "screwdriver")


def test_grasps_restricted_to_an_affordance_touch_only_it(screwdriver):
    grasps = plan_grasps(screwdriver, PlanConfig(affordance="screw", num=8, refine=RefineConfig(steps=0)))
    assert grasps
    assert all(g.affordance == ["screw", "screw"] for g in grasps)
    assert [g.epsilon for g in grasps] == sorted((g.epsilon for g in grasps), reverse=True)


def _strip(n: int = 41) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A flat strip 0.4 m long along x, of n - 1 squares; the part is x < 0.1 (a quarter of it)."""
    x = np.linspace(-0.2, 0.2, n)
    vertices = np.concatenate(
        [np.stack([x, np.zeros(n), np.zeros(n)], 1), np.stack([x, np.ones(n) * 0.01, np.zeros(n)], 1)]
    )
    faces = np.concatenate([[[i, i + 1, n + i], [i + 1, n + i + 1, n + i]] for i in range(n - 1)])
    part = vertices[faces].mean(axis=1)[:, 0] < -0.1
    return vertices, faces, part


def test_shrinking_a_part_keeps_only_faces_that_far_from_other_labels():
    vertices, faces, part = _strip()
    kept = shrink_part(vertices, faces, part, 0.03)
    centre_x = vertices[faces].mean(axis=1)[:, 0]
    assert kept.any() and not (kept & ~part).any()
    assert centre_x[kept].max() <= -0.1 - 0.03 + 1e-9 < centre_x[part & ~kept].min()
    assert np.array_equal(shrink_part(vertices, faces, part, 0.0), part)


def test_a_part_thinner_than_the_margin_is_shrunk_less_never_emptied():
    vertices, faces, part = _strip()
    kept = shrink_part(vertices, faces, part, 0.15)  # the part is 0.1 long: 0.15 and 0.075 leave nothing, 0.0375 does
    centre_x = vertices[faces].mean(axis=1)[:, 0]
    assert kept.any() and centre_x[kept].max() <= -0.1 - 0.0375 + 1e-9
    lone = np.zeros(len(faces), bool)
    lone[[0, 1]] = True  # a part narrower than every halving keeps all of itself
    assert np.array_equal(shrink_part(vertices, faces, lone, 0.5), lone)


def test_a_margin_keeps_restricted_contacts_away_from_the_parts_boundary(screwdriver):
    shaft = screwdriver.face_affordance == AFFORDANCE_CLASSES.index("screw")
    others = np.unique(screwdriver.faces[~shaft])
    config = PlanConfig(affordance="screw", num=8, refine=RefineConfig(steps=0), part_margin=0.02)
    grasps = plan_grasps(screwdriver, config)
    assert grasps
    contacts = np.concatenate([g.contacts for g in grasps])
    gap = np.linalg.norm(contacts[:, None] - screwdriver.vertices[others][None], axis=-1).min(axis=1)
    assert gap.min() > 0.02 - 0.01  # faces are kept by their centroid: a contact may sit up to a face's size closer


def test_a_margin_that_leaves_only_ungraspable_surface_falls_back_to_the_whole_part():
    body = trimesh.creation.box((0.04, 0.04, 0.04))  # another label
    bar = trimesh.creation.box((0.06, 0.012, 0.012), trimesh.transformations.translation_matrix((0.05, 0, 0)))
    block = trimesh.creation.box((0.3, 0.3, 0.3), trimesh.transformations.translation_matrix((0.5, 0, 0)))
    meshes = (body, bar, block)
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes])[:-1]
    vertices = np.concatenate([m.vertices for m in meshes])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets, strict=True)])
    grasp, other = AFFORDANCE_CLASSES.index("grasp"), AFFORDANCE_CLASSES.index("screw")
    labels = np.concatenate([np.full(len(m.faces), lab) for m, lab in zip(meshes, (other, grasp, grasp), strict=True)])
    obj = GraspObject(vertices, faces, labels, "bar and block")
    config = PlanConfig(affordance="grasp", num=4, refine=RefineConfig(steps=0), part_margin=0.1)
    shrunk = vertices[faces[shrink_part(vertices, faces, labels == grasp, 0.1)]].mean(axis=1)
    assert shrunk[:, 0].min() > 0.3  # only the block is 0.1 from the body: it is wider than any opening
    grasps = plan_grasps(obj, config)
    assert grasps and all(np.all(g.contacts[:, 0] < 0.1) for g in grasps)  # on the bar, as without a margin


def test_restricted_grasps_go_first_where_a_second_prediction_confirms_the_part(screwdriver):
    handle = screwdriver.face_affordance == AFFORDANCE_CLASSES.index("grasp")
    centre_x = screwdriver.vertices[screwdriver.faces].mean(axis=1)[:, 0]
    agrees = handle & (centre_x < -0.15)  # the handle spans x in [-0.22, -0.056]: its far end is confirmed
    obj = GraspObject(screwdriver.vertices, screwdriver.faces, screwdriver.face_affordance, "screwdriver", agrees)
    config = PlanConfig(affordance="grasp", num=8, refine=RefineConfig(steps=0), part_margin=0.0)
    grasps = plan_grasps(obj, config)
    assert grasps and all(g.affordance == ["grasp", "grasp"] for g in grasps)
    assert max(g.contacts[:, 0].max() for g in grasps) < -0.15 + 0.005  # faces are kept by their centroid
    unconfirmed = plan_grasps(screwdriver, config)
    assert max(g.contacts[:, 0].max() for g in unconfirmed) > -0.15


def test_a_confirmed_patch_without_grasps_falls_back_to_the_whole_part(screwdriver):
    handle = screwdriver.face_affordance == AFFORDANCE_CLASSES.index("grasp")
    agrees = np.zeros_like(handle)
    agrees[np.flatnonzero(handle)[:2]] = True  # two faces: no antipodal pair lies on them
    obj = GraspObject(screwdriver.vertices, screwdriver.faces, screwdriver.face_affordance, "screwdriver", agrees)
    masks = part_masks(obj, handle, 0.01)
    assert np.array_equal(masks[0], agrees) and np.array_equal(masks[-1], handle)
    assert all(not (m & ~handle).any() for m in masks)
    assert not any(np.array_equal(a, b) for i, a in enumerate(masks) for b in masks[i + 1 :])  # none planned twice
    grasps = plan_grasps(obj, PlanConfig(affordance="grasp", num=4, refine=RefineConfig(steps=0)))
    assert grasps and all(g.affordance == ["grasp", "grasp"] for g in grasps)


def test_restricted_grasps_go_first_where_the_field_is_sure_of_the_part(screwdriver):
    centre_x = screwdriver.vertices[screwdriver.faces].mean(axis=1)[:, 0]
    confidence = np.where(centre_x < -0.15, 0.95, 0.6)  # the handle's far end is the sure part
    obj = GraspObject(
        screwdriver.vertices, screwdriver.faces, screwdriver.face_affordance, "screwdriver", None, confidence
    )
    config = PlanConfig(affordance="grasp", num=8, refine=RefineConfig(steps=0), part_margin=0.0, min_confidence=0.8)
    grasps = plan_grasps(obj, config)
    assert grasps and max(g.contacts[:, 0].max() for g in grasps) < -0.15 + 0.005
    unsure = plan_grasps(obj, replace(config, min_confidence=PlanConfig().min_confidence))  # the default: off
    assert max(g.contacts[:, 0].max() for g in unsure) > -0.15


def test_the_vouched_part_needs_both_agreement_and_confidence_where_the_mesh_has_them():
    part = np.array([True, True, True, True, False])
    agrees = np.array([True, True, False, True, True])
    confidence = np.array([0.9, 0.5, 0.9, 0.8, 0.9])
    obj = GraspObject(np.zeros((3, 3)), np.zeros((5, 3), np.int64), None, "m", agrees, confidence)
    assert trusted_part(obj, part, 0.8).tolist() == [True, False, False, True, False]  # 0.8 itself passes
    assert trusted_part(obj, part, 0.0).tolist() == [True, True, False, True, False]
    assert trusted_part(replace(obj, face_agrees=None), part, 0.95) is None  # nothing that sure
    assert trusted_part(replace(obj, face_agrees=None), part, 0.4) is None  # the whole part: no first try
    assert trusted_part(replace(obj, face_agrees=None, face_confidence=None), part, 0.8) is None


def test_planned_grasps_are_valid_and_collision_free(screwdriver):
    gripper = ParallelJawGripper()
    grasps = plan_grasps(screwdriver, PlanConfig(num=10, refine=RefineConfig(steps=5)))
    assert len(grasps) == 10 and all(g.epsilon > 0 for g in grasps)
    dense = np.concatenate([screwdriver.sample_surface(20000, np.random.default_rng(9))[0], screwdriver.vertices])
    poses = np.stack([g.pose for g in grasps])
    widths = np.array([g.width for g in grasps])
    assert not collides(poses, widths, gripper, dense, tolerance=0.002).any()
    assert all(0 < g.width <= gripper.max_opening for g in grasps)
    for g in grasps:  # both contacts lie on the closing line's pads, opening apart
        local = (g.contacts - g.pose[:3, 3]) @ g.pose[:3, :3]
        assert local[0, 0] < 0 < local[1, 0]
        assert abs((local[1, 0] - local[0, 0]) - g.width) < 1.5e-3  # contacts are patch centres, width the first touch


def test_the_collision_check_agrees_with_testing_every_point_in_every_solid():
    rng = np.random.default_rng(3)
    gripper = ParallelJawGripper()
    points = rng.uniform(-0.15, 0.15, (4000, 3))
    centres = rng.uniform(-0.1, 0.1, (200, 3))
    poses = np.stack([grasp_pose(c, rng.normal(size=3), rng.normal(size=3)) for c in centres])
    widths = rng.uniform(0.0, gripper.max_opening, 200)
    expected = np.zeros(200, bool)
    for i, (pose, width) in enumerate(zip(poses, widths, strict=True)):
        local = (points - pose[:3, 3]) @ pose[:3, :3]
        for centre, half in gripper.boxes(width):
            expected[i] |= np.all(np.abs(local - centre) < half - 0.001, axis=1).any()
            corners = centre + half * np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
            assert np.linalg.norm(corners, axis=1).max() <= gripper.reach(width) + 1e-12
    assert 0 < expected.sum() < 200
    assert np.array_equal(collides(poses, widths, gripper, points, tolerance=0.001), expected)
    assert not collides(poses[:0], widths[:0], gripper, points, 0.001).any()
    assert not collides(poses, widths, gripper, points[:0], 0.001).any()


def test_local_search_lowers_the_energy(screwdriver):
    rng = np.random.default_rng(0)
    gripper = ParallelJawGripper()
    centres, axes, widths = sample_antipodal(screwdriver, 32, rng, None, 0.5, gripper)
    approach = np.cross(axes, np.array([0.0, 0.0, 1.0]))
    approach /= np.linalg.norm(approach, axis=1, keepdims=True)
    centres = centres + rng.normal(0, 0.004, centres.shape)  # knocked off the surface
    surface, faces = screwdriver.sample_surface(1500, rng)
    normals = screwdriver.face_normals[faces]
    config = RefineConfig(steps=30)
    args = (
        torch.tensor(surface, dtype=torch.float32),
        torch.tensor(normals, dtype=torch.float32),
        torch.tensor(screwdriver.centroid, dtype=torch.float32),
        screwdriver.radius,
        gripper,
        config,
    )

    def energy(c, a, r, w):
        t = [torch.tensor(np.asarray(x), dtype=torch.float32) for x in (c, a, r, w)]
        return grasp_energy(*t, *args).detach().numpy()

    before = energy(centres, axes, approach, widths)
    after = energy(
        *refine_grasps(
            centres, axes, approach, widths, surface, normals, screwdriver.centroid, screwdriver.radius, gripper, config
        )
    )
    assert np.median(after) < 0.5 * np.median(before)


def _write(path, mesh: trimesh.Trimesh, labels=True, poison=False):
    vertices = np.array(mesh.vertices, np.float64)
    if poison:
        vertices[0, 0] = np.nan
    props = {"affordance": np.ones(len(mesh.faces), np.uint8)} if labels else {}
    write_labelled_ply(path, LabelledMesh(vertices, np.asarray(mesh.faces), face_props=props))
    return path


def test_cli_plans_and_scores(tmp_path, capsys):
    mesh = _write(tmp_path / "box.ply", trimesh.creation.box(extents=(0.04, 0.05, 0.12)))
    out = tmp_path / "g"
    assert (
        main(
            [
                "grasp",
                "--mesh",
                str(mesh),
                "--affordance",
                "grasp",
                "--num",
                "4",
                "--refine-steps",
                "3",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    data = json.loads((out / "grasps.json").read_text())
    assert len(data["grasps"]) == 4 and data["affordance"] == "grasp"
    g0 = data["grasps"][0]
    assert np.asarray(g0["pose"]).shape == (4, 4) and len(g0["contacts"]) == 2 and g0["affordance"] == ["grasp"] * 2
    assert (out / "grasps.glb").stat().st_size > 0 and (out / "grasps.png").stat().st_size > 0
    capsys.readouterr()
    assert (
        main(
            [
                "grasp",
                "score",
                "--mesh",
                str(mesh),
                "--grasps",
                str(out / "grasps.json"),
                "--out",
                str(tmp_path / "s.json"),
            ]
        )
        == 0
    )
    scores = json.loads((tmp_path / "s.json").read_text())["scores"]
    assert scores[0]["epsilon"] == pytest.approx(g0["epsilon"], rel=1e-3)  # the file rounds poses to micrometres
    assert scores[0]["affordance"] == ["grasp", "grasp"]
    assert AFFORDANCE_CLASSES[1] == "grasp"


@pytest.mark.parametrize(
    "case, expected",
    [
        ("unlabelled", r"box\.ply: mesh has no 'affordance' property"),
        ("nonfinite", r"box\.ply: mesh has non-finite vertices"),
        ("empty", r"box\.ply: mesh has no faces"),
        ("bad_grasps", r"grasps\.json: grasp 0 needs 'pose' and 'width'"),
        ("nan_pose", r"grasps\.json: grasp 0 pose has NaN"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, case, expected):
    import re

    box = trimesh.creation.box(extents=(0.04, 0.05, 0.12))
    path = tmp_path / "box.ply"
    if case == "empty":
        path.write_text(
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 0\nproperty list uchar int vertex_indices\nend_header\n"
        )
    else:
        _write(path, box, labels=case != "unlabelled", poison=case == "nonfinite")
    if case in ("bad_grasps", "nan_pose"):
        grasps = tmp_path / "grasps.json"
        pose = np.eye(4).tolist()
        if case == "nan_pose":
            pose[0][3] = float("nan")
        grasps.write_text(
            json.dumps({"grasps": [{"pose": pose, "width": 0.04} if case == "nan_pose" else {"width": 1}]})
        )
        code = main(["grasp", "score", "--mesh", str(path), "--grasps", str(grasps)])
    else:
        code = main(["grasp", "--mesh", str(path), "--affordance", "grasp", "--out", str(tmp_path / "o")])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(expected, err[0]), err


def test_a_wider_clearance_keeps_grasps_clear_of_the_opening():
    # a 0.07 x 0.07 x 0.3 m bar fits the 0.08 m gripper only across its 0.07 m sides
    bar = trimesh.creation.box((0.07, 0.07, 0.3))
    obj = GraspObject(np.asarray(bar.vertices), np.asarray(bar.faces), None, "bar")
    plan = PlanConfig(num=8, refine=RefineConfig(steps=0))
    grasps = plan_grasps(obj, plan)
    assert grasps and all(0.069 < g.width <= 0.08 - 0.004 for g in grasps)
    assert plan_grasps(obj, PlanConfig(num=8, refine=RefineConfig(steps=0), width_clearance=0.015)) == []


def test_a_mesh_predict_wrote_is_planned_with_the_predicted_clearance(tmp_path):
    from affnerf.grasp.io import default_clearance
    from affnerf.grasp.planner import PREDICTED_CLEARANCE, WIDTH_CLEARANCE

    mesh = tmp_path / "affordance_model.ply"
    assert default_clearance(mesh) == WIDTH_CLEARANCE  # a dataset or user mesh
    (tmp_path / "prediction.json").write_text("{}")
    assert default_clearance(mesh) == PREDICTED_CLEARANCE > WIDTH_CLEARANCE


def test_ranking_by_hold_orders_by_the_weight_carried_through_the_turn(screwdriver):
    config = PlanConfig(num=12, refine=RefineConfig(steps=0))
    by_epsilon = plan_grasps(screwdriver, config)
    by_hold = plan_grasps(screwdriver, replace(config, rank="hold"))
    holds = [g.hold for g in by_hold]
    assert holds == sorted(holds, reverse=True) and holds[0] > 0
    epsilons = [g.epsilon for g in by_epsilon]
    assert epsilons == sorted(epsilons, reverse=True)
    # the same candidates, ranked another way: the best hold is found first, and the epsilon ranking's is no better
    assert by_hold[0].hold >= max(g.hold for g in by_epsilon)
    assert by_hold[0].to_json()["hold"] == pytest.approx(by_hold[0].hold, abs=1e-6)
