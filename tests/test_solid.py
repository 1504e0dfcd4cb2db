"""Solids bounded by meshes: the outer surface of an object made of parts that overlap."""

from __future__ import annotations

import numpy as np
import trimesh

from affnerf.solid import keep_outer, outer_samples


def _cube_with_sunk_peg() -> trimesh.Trimesh:
    """A 0.2 m cube with a 0.04 x 0.04 x 0.2 m peg through its top: the peg's lower 0.1 m lies inside the cube."""
    cube = trimesh.creation.box(extents=(0.2, 0.2, 0.2))
    peg = trimesh.creation.box(
        extents=(0.04, 0.04, 0.2), transform=trimesh.transformations.translation_matrix((0, 0, 0.1))
    )
    return trimesh.util.concatenate([cube, peg])


def test_faces_sunk_into_another_part_are_not_outer_surface():
    mesh = _cube_with_sunk_peg()
    samples, faces = trimesh.sample.sample_surface(mesh, 20000, seed=0)
    outer = outer_samples(mesh, samples, np.asarray(faces))
    peg = np.asarray(faces) >= 12
    in_cube = np.abs(samples).max(axis=1) < 0.1 - 1e-3
    under_peg = ~peg & (np.abs(samples[:, :2]).max(axis=1) < 0.02 - 1e-3) & (samples[:, 2] > 0.1 - 1e-6)
    assert (peg & in_cube).sum() > 100 and not outer[peg & in_cube].any()  # the peg's sunk half
    assert under_peg.sum() > 5 and not outer[under_peg].any()  # the cube's top where the peg covers it
    clear_of_peg = ~peg & (np.abs(samples[:, :2]).max(axis=1) > 0.02 + 1e-3)
    assert outer[peg & (samples[:, 2] > 0.1 + 1e-3)].all() and outer[clear_of_peg].all()


def test_keep_outer_drops_hidden_samples_and_keeps_all_when_the_mesh_cannot_be_read():
    mesh = _cube_with_sunk_peg()
    samples, faces = trimesh.sample.sample_surface(mesh, 5000, seed=1)
    kept, kept_faces = keep_outer(mesh, samples, np.asarray(faces))
    assert 0.7 * len(samples) < len(kept) < len(samples) and len(kept) == len(kept_faces)
    inner = trimesh.creation.box(extents=(0.1, 0.1, 0.1))  # wholly inside the cube: nothing of it is outer ...
    both = trimesh.util.concatenate([trimesh.creation.box(extents=(0.2, 0.2, 0.2)), inner])
    points = np.array([[0.0, 0.0, 0.05], [0.05, 0.0, 0.0]])  # ... so two samples on it are all hidden: kept
    assert len(keep_outer(both, points, np.array([12, 12]))[0]) == 2
    assert len(keep_outer(both, points[:0], np.zeros(0, np.int64))[0]) == 0
