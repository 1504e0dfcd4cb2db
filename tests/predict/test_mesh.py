"""Marching cubes on analytic fields (the surface is where it should be and labels carry over), and the level a
trained model's mesh is cut at."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import torch
import trimesh

from affnerf.meshio import LabelledMesh, majority_face_labels
from affnerf.predict.level import object_level
from affnerf.predict.loading import load_model
from affnerf.predict.mesh import class_areas, evaluate_grid, extract_labelled_mesh, face_confidence, model_surface


def _sphere(radius: float, sharpness: float = 0.01):
    return lambda p: 100.0 * torch.clamp((radius - p.norm(dim=-1)) / sharpness + 0.5, 0.0, 1.0)


def test_sphere_field_gives_the_sphere_within_a_voxel():
    resolution = 64
    voxel = 0.5 / (resolution - 1)
    mesh = extract_labelled_mesh(
        _sphere(0.15), lambda p: torch.where(p[:, 2] > 0, 1, 7), resolution, level=50.0, half_extent=0.25
    )
    radius = np.linalg.norm(mesh.vertices, axis=1)
    assert np.abs(radius - 0.15).max() < voxel
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces)
    assert tm.is_watertight and tm.volume > 0  # closed, normals outward
    np.testing.assert_allclose(tm.volume, 4 / 3 * np.pi * 0.15**3, rtol=0.02)
    up = mesh.vertices[:, 2] > 0
    assert np.all(mesh.vertex_props["affordance"][up] == 1) and np.all(mesh.vertex_props["affordance"][~up] == 7)
    areas = class_areas(mesh)
    np.testing.assert_allclose(areas[1], areas[7], rtol=0.05)
    np.testing.assert_allclose(areas[1] + areas[7], 4 * np.pi * 0.15**2, rtol=0.02)
    assert np.all(mesh.vertex_colors[up] == [230, 25, 75])  # grasp's palette colour


def test_empty_field_gives_an_empty_mesh():
    mesh = extract_labelled_mesh(lambda p: torch.zeros(len(p)), lambda p: torch.ones(len(p)), 16, 50.0, 0.25)
    assert len(mesh.faces) == 0 and len(mesh.vertices) == 0


def test_face_label_is_the_majority_of_its_vertices():
    faces = np.array([[0, 1, 2], [0, 1, 3], [1, 2, 3]])
    labels = np.array([4, 4, 5, 5])
    assert majority_face_labels(faces, labels).tolist() == [4, 4, 5]


def test_an_objects_own_level_is_the_one_the_mesh_is_cut_at(trained_runs):
    """With ``surface_optical_depth`` set, model_surface cuts at object_level of the same grid; a given level wins."""
    model = load_model(trained_runs["affnerf"], "cpu").model
    model.config = replace(model.config, surface_density=2.0, surface_optical_depth=0.01)
    codes = model.encode(torch.rand(1, 3, model.config.encoder_resolution, model.config.encoder_resolution))
    half = model.config.scene_half_extent
    volume = evaluate_grid(model.point_fields(codes)[0], 20, half)
    expected = object_level(volume, 2 * half / 19, 2.0, 0.01)
    mesh, level = model_surface(model, codes, resolution=20)
    assert level == expected <= 2.0
    assert model_surface(model, codes, resolution=20, level=0.7)[1] == 0.7
    model.config = replace(model.config, surface_optical_depth=0.0)
    assert model_surface(model, codes, resolution=20)[1] == 2.0


def test_a_models_mesh_says_how_sure_the_field_is_of_each_faces_label(trained_runs):
    model = load_model(trained_runs["affnerf"], "cpu").model
    codes = model.encode(torch.rand(1, 3, model.config.encoder_resolution, model.config.encoder_resolution))
    volume = evaluate_grid(model.point_fields(codes)[0], 20, model.config.scene_half_extent)
    level = float(np.quantile(volume, 0.9))  # a level this tiny run's field crosses, whatever it learned
    mesh, _ = model_surface(model, codes, resolution=20, level=level)
    assert len(mesh.faces), "a level inside the field's range gives a surface"
    confidence = mesh.face_props["confidence"]
    centres = torch.from_numpy(mesh.vertices[mesh.faces].mean(axis=1)).float()
    p = model.point_probabilities(codes)(centres).detach().numpy()
    own = p[np.arange(len(p)), mesh.face_props["affordance"].astype(int) - 1]
    assert confidence.dtype == np.uint8 and np.all(np.abs(confidence - own * 100) <= 1.0)


def test_face_confidence_reads_the_probability_of_each_faces_own_label():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    mesh = LabelledMesh(vertices, np.array([[0, 1, 2], [1, 3, 2]]), face_props={"affordance": np.array([1, 3])})
    probabilities = lambda p: torch.tensor([0.8, 0.15, 0.05]).expand(len(p), 3)  # noqa: E731
    assert face_confidence(mesh, probabilities).tolist() == [80, 5]
