"""``affnerf view``: the scene built from a prediction-like folder, errors on bad input, and the page rendered in
headless Chromium (skipped where no Chromium is installed; CI installs Debian's ``chromium``)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh
from PIL import Image

from affnerf.errors import AffnerfError
from affnerf.grasp.gripper import ParallelJawGripper, grasp_pose
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.vocab import AFFORDANCE_PALETTE, colorize_labels

viser = pytest.importorskip("viser")

from affnerf.viewer import build_scene, serve  # noqa: E402
from affnerf.viewer.headless import find_chromium, screenshot  # noqa: E402

GRASP, CUT = 1, 2  # the two classes of the test object: top half grasp (red), bottom half cut (green)


def write_prediction_folder(out: Path) -> Path:
    """A folder shaped like ``affnerf predict``'s: a labelled sphere, two grasps (in grasps/) and an input image."""
    out.mkdir(parents=True, exist_ok=True)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.08)
    vertex_labels = np.where(sphere.vertices[:, 2] > 0, GRASP, CUT).astype(np.uint8)
    face_labels = np.where(sphere.triangles_center[:, 2] > 0, GRASP, CUT).astype(np.uint8)
    mesh = LabelledMesh(
        np.asarray(sphere.vertices),
        np.asarray(sphere.faces),
        {"affordance": vertex_labels},
        {"affordance": face_labels},
        colorize_labels(vertex_labels),
    )
    write_labelled_ply(out / "affordance_model.ply", mesh)
    top = grasp_pose(np.array([0.0, 0.0, 0.05]), np.array([1.0, 0, 0]), np.array([0, 0, -1.0]))
    side = grasp_pose(np.zeros(3), np.array([0, 0, 1.0]), np.array([0, 1.0, 0]))
    grasps = [
        {
            "pose": top.tolist(),
            "width": 0.06,
            "contacts": [[-0.03, 0, 0.05], [0.03, 0, 0.05]],
            "epsilon": 0.02,
            "affordance": ["grasp", "grasp"],
        },
        {
            "pose": side.tolist(),
            "width": 0.07,
            "contacts": [[0, 0, -0.035], [0, 0, 0.035]],
            "epsilon": 0.01,
            "affordance": ["cut", "grasp"],
        },
    ]
    (out / "grasps").mkdir(exist_ok=True)
    payload = {
        "format": "affnerf-grasps-1",
        "mesh": str(out / "affordance_model.ply"),
        "affordance": "grasp",
        "gripper": {"type": "parallel", **ParallelJawGripper().__dict__},
        "grasps": grasps,
    }
    (out / "grasps" / "grasps.json").write_text(json.dumps(payload))
    image = np.full((96, 128, 3), 240, np.uint8)
    image[24:72, 40:88] = AFFORDANCE_PALETTE[GRASP]
    Image.fromarray(image).save(out / "input.png")
    return out


@pytest.fixture
def prediction(tmp_path: Path) -> Path:
    return write_prediction_folder(tmp_path / "pred")


@pytest.fixture
def server():
    srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield srv
    srv.stop()


def test_build_scene_from_prediction_folder(server, prediction: Path) -> None:
    handles = build_scene(server, prediction, top_k=1)
    assert set(handles.meshes) == {GRASP, CUT} and set(handles.toggles) == {GRASP, CUT}
    assert [p.name for p in handles.content.parts] == ["grasp", "cut"]
    assert handles.content.sources.grasps == prediction / "grasps" / "grasps.json"
    assert len(handles.grippers) == 2 and handles.top_k is not None
    assert [g.visible for g in handles.grippers] == [True, False]
    handles.top_k.value = 2
    assert [g.visible for g in handles.grippers] == [True, True]
    handles.toggles[CUT].value = False
    assert not handles.meshes[CUT].visible and handles.meshes[GRASP].visible
    camera = handles.content.sources.camera
    assert camera is not None and not camera.exact and "pose-free" in camera.note
    # The stand-in camera is the first turntable camera: in front of the object (-y), above it, looking at it.
    position = handles.frustum.position
    assert position[1] < -0.5 and position[2] > 0.2
    forward = handles.frustum.wxyz  # OpenCV +z (forward) of the frustum points at the origin
    rot = viser.transforms.SO3(np.asarray(forward)).as_matrix()
    assert np.dot(rot[:, 2], -position / np.linalg.norm(position)) > 0.99
    assert np.allclose(handles.centre, 0.0, atol=1e-3)
    assert math.isclose(handles.radius, 0.08 * math.sqrt(3), rel_tol=0.05)


def test_build_scene_from_mesh_file_and_grasps_folder(server, prediction: Path) -> None:
    handles = build_scene(server, prediction / "affordance_model.ply")
    assert set(handles.meshes) == {GRASP, CUT}
    grasps_folder = build_scene(server, prediction / "grasps")
    assert grasps_folder.content.sources.mesh == prediction / "affordance_model.ply"
    assert len(grasps_folder.grippers) == 2


def test_unlabelled_glb_is_one_part(server, tmp_path: Path) -> None:
    path = tmp_path / "box.glb"
    path.write_bytes(trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(file_type="glb"))
    handles = build_scene(server, path)
    assert list(handles.meshes) == [None] and handles.frustum is None and not handles.grippers


def test_dataset_object_shows_frame_zero_camera(server, tiny_dataset: Path) -> None:
    folder = next(p.parent for p in sorted(tiny_dataset.rglob("transforms.json")))
    handles = build_scene(server, folder)
    camera = handles.content.sources.camera
    meta = json.loads((folder / "transforms.json").read_text())
    c2w = np.array(meta["frames"][0]["transform_matrix"])
    assert camera is not None and camera.exact and camera.image == folder / meta["frames"][0]["file_path"]
    assert np.allclose(handles.frustum.position, c2w[:3, 3], atol=1e-5)
    rot = viser.transforms.SO3(np.asarray(handles.frustum.wxyz)).as_matrix()
    assert np.allclose(rot[:, 2], -c2w[:3, 2], atol=1e-4)  # OpenCV forward = OpenGL -z
    assert handles.content.image is not None and all(p.label is not None for p in handles.content.parts)


@pytest.mark.parametrize(
    ("make", "problem"),
    [
        (lambda d: d / "missing", "not found"),
        (lambda d: d, "no mesh in this folder"),
        (lambda d: (d / "notes.txt").write_text("x") and d / "notes.txt", "not a mesh file"),
    ],
)
def test_bad_input_names_the_path(tmp_path: Path, make, problem: str) -> None:
    from affnerf.viewer import load_content

    path = make(tmp_path)
    with pytest.raises(AffnerfError, match=problem) as info:
        load_content(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_mesh_without_faces_is_an_error(tmp_path: Path) -> None:
    from affnerf.viewer import load_content

    path = tmp_path / "points.ply"
    path.write_bytes(trimesh.PointCloud(np.random.default_rng(0).random((10, 3))).export(file_type="ply"))
    with pytest.raises(AffnerfError, match="no faces") as info:
        load_content(path)
    assert str(path) in str(info.value)


def hue_saturation(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 3) uint8 colours -> hue in degrees [0, 360) and saturation (max - min) / max."""
    c = rgb[..., :3].astype(np.float64) / 255.0
    hi, lo = c.max(-1), c.min(-1)
    span = np.maximum(hi - lo, 1e-9)
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    hue = np.where(hi == r, (g - b) / span % 6.0, np.where(hi == g, (b - r) / span + 2.0, (r - g) / span + 4.0))
    return hue * 60.0, (hi - lo) / np.maximum(hi, 1e-9)


def palette_pixels(image: np.ndarray, label: int, degrees: float = 12.0) -> np.ndarray:
    """(H, W) bool: saturated pixels within ``degrees`` of hue of a class's palette colour (hue, unlike RGB
    distance, survives the viewer's shading)."""
    hue, sat = hue_saturation(image)
    target, _ = hue_saturation(AFFORDANCE_PALETTE[label])
    gap = np.abs(hue - target)
    return (sat > 0.35) & (np.minimum(gap, 360.0 - gap) < degrees)


def canvas_region(image: np.ndarray) -> np.ndarray:
    """The middle of the 3D canvas, left of viser's GUI panel (which floats at the top right and also shows the
    legend's palette swatches)."""
    h, w = image.shape[:2]
    return image[h // 8 : h - h // 8, w // 8 : int(w * 0.64)]


@pytest.mark.slow
def test_page_renders_the_mesh_in_headless_chromium(prediction: Path, tmp_path: Path) -> None:
    chromium = find_chromium()
    if chromium is None:
        pytest.skip("no Chromium installed (`apt-get install chromium`; .ci/run installs it)")
    srv = serve(prediction, host="127.0.0.1", port=0, block=False)
    try:
        url = f"http://127.0.0.1:{srv.get_port()}"

        def mesh_drawn(image: np.ndarray) -> bool:
            region = canvas_region(image)
            return all(palette_pixels(region, c).sum() > 2000 for c in (GRASP, CUT))

        image = screenshot(url, until=mesh_drawn, timeout=150.0, chromium=chromium)
    finally:
        srv.stop()
    Image.fromarray(image).save(tmp_path / "viewer.png")
    region = canvas_region(image)
    counts = {c: int(palette_pixels(region, c).sum()) for c in (GRASP, CUT)}
    distinct = len(np.unique(region.reshape(-1, 3), axis=0))
    where = f"screenshot: {tmp_path / 'viewer.png'}"
    assert distinct > 500, f"the 3D canvas looks blank ({distinct} distinct colours); {where}"
    assert min(counts.values()) > 2000, f"the affordance classes are not drawn (pixels per class {counts}); {where}"


def test_metric_grasps_are_drawn_on_the_canonical_mesh(tmp_path):
    """A grasps.json in the metric frame (size.scale 2: the canonical mesh is twice the real object) is brought
    back to the mesh: positions and the gripper itself grow by the scale."""
    from affnerf.grasp.io import write_grasps
    from affnerf.grasp.planner import Grasp
    from affnerf.viewer.loading import load_grasps

    hand = ParallelJawGripper()
    pose = grasp_pose(np.array([0.01, 0.02, 0.03]), np.array([1.0, 0, 0]), np.array([0, 0, -1.0]))
    grasp = Grasp(pose=pose, width=0.04, contacts=np.zeros((2, 3)), epsilon=0.01, affordance=["grasp", "grasp"])
    plain, metric = tmp_path / "plain.json", tmp_path / "metric.json"
    write_grasps(plain, [grasp], "mesh.ply", "grasp", hand)
    write_grasps(metric, [grasp], "mesh.ply", "grasp", hand, {"scale": 2.0, "largest_side": 0.2, "source": "test"})
    (a,), (b,) = load_grasps(plain), load_grasps(metric)
    assert np.allclose(b.pose[:3, 3], 2 * a.pose[:3, 3]) and np.allclose(b.pose[:3, :3], a.pose[:3, :3])
    assert np.allclose(b.mesh.extents, 2 * a.mesh.extents)
    assert b.width == a.width == 0.04  # the opening is reported in metres


def test_a_fitted_prediction_shows_its_input_at_the_camera_the_fit_found(tmp_path: Path) -> None:
    from affnerf.data.cameras import look_at
    from affnerf.viewer.sources import find_camera

    folder = write_prediction_folder(tmp_path / "pred")
    c2w = look_at(np.array([0.3, 0.4, 0.5]), np.zeros(3))
    summary = {"fit": {"camera": {"c2w": c2w.tolist(), "crop_fov_deg": 20.0}}}
    (folder / "prediction.json").write_text(json.dumps(summary))
    camera = find_camera(folder)
    assert camera is not None and not camera.exact and "fit" in camera.note
    np.testing.assert_allclose(camera.c2w, c2w)
    assert math.isclose(camera.fov_y, math.radians(20.0)) and camera.aspect == 1.0
    (folder / "prediction.json").write_text(json.dumps({"fit": None}))  # --fit-steps 0: the stand-in again
    assert "pose-free" in find_camera(folder).note
