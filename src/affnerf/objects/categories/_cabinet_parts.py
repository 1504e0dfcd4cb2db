"""Geometry of a cabinet's pieces: carcass, base, fronts, drawer boxes and handles, and the joint transforms.

Every function returns closed, consistently wound meshes; a piece made of several boards is the concatenation of
closed boxes (touching or overlapping), which stays watertight and consistently wound. Coordinates follow
:mod:`affnerf.objects.categories.cabinet`: +z up, the front faces -y.
"""

from __future__ import annotations

import numpy as np
import trimesh

from affnerf.objects.primitives import box, ellipsoid, placed, revolve, rotation, translation


def board(lo: tuple[float, float, float] | np.ndarray, hi: tuple[float, float, float] | np.ndarray) -> trimesh.Trimesh:
    """An axis-aligned box spanning the corners ``lo`` and ``hi`` (each (3,))."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    return placed(box(hi - lo), translation((lo + hi) / 2.0))


def join(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """One mesh holding several closed pieces, each kept as its own closed component."""
    return trimesh.util.concatenate(meshes)


def carcass(
    width: float, depth: float, height: float, thickness: float, z0: float, overhang: float, dividers: list[float]
) -> trimesh.Trimesh:
    """The open-front box: two sides, bottom, back, a top slab over everything and horizontal dividers.

    Args:
        width, depth, height: outer size of the box below the top slab.
        thickness: board thickness.
        z0: height of the carcass's underside.
        overhang: how far the top slab reaches past the sides and the front.
        dividers: heights of the dividers' centres (between drawers, and above the doors).
    """
    w, d, t = width / 2.0, depth / 2.0, thickness
    z1 = z0 + height
    boards = [
        board((-w, -d, z0), (-w + t, d, z1)),
        board((w - t, -d, z0), (w, d, z1)),
        board((-w + t, -d, z0), (w - t, d, z0 + t)),
        board((-w + t, d - t, z0 + t), (w - t, d, z1)),
        board((-w - overhang, -d - overhang, z1), (w + overhang, d, z1 + t)),
    ]
    boards += [board((-w + t, -d, zc - t / 2), (w - t, d - t, zc + t / 2)) for zc in dividers]
    return join(boards)


def plinth(width: float, depth: float, height: float, inset: float) -> trimesh.Trimesh:
    """A recessed block under the carcass, set back by ``inset`` on every side."""
    return board((-width / 2 + inset, -depth / 2 + inset, 0.0), (width / 2 - inset, depth / 2 - inset, height))


def legs(width: float, depth: float, height: float, inset: float, radius: float) -> trimesh.Trimesh:
    """Four round legs tapering towards the floor, ``inset`` from the carcass's corners."""
    leg = revolve(np.array([[0.6 * radius, 0.0], [radius, 0.8 * height], [radius, height]]), segments=24)
    x, y = width / 2 - inset - radius, depth / 2 - inset - radius
    return join([placed(leg, translation((sx * x, sy * y, 0.0))) for sx in (-1, 1) for sy in (-1, 1)])


def front_panel(lo: np.ndarray, hi: np.ndarray, framed: bool) -> trimesh.Trimesh:
    """A door or drawer front spanning ``lo``..``hi`` (its back face at ``hi[1]``).

    A framed (shaker) front is a thinner centre panel inside four full-thickness rails.
    """
    if not framed:
        return board(lo, hi)
    size = hi - lo
    rail = min(0.06, 0.16 * min(size[0], size[2]))
    thin = np.array([lo[0], lo[1] + 0.4 * size[1], lo[2]])
    rails = [
        board(lo, (lo[0] + rail, hi[1], hi[2])),
        board((hi[0] - rail, lo[1], lo[2]), hi),
        board((lo[0] + rail, lo[1], lo[2]), (hi[0] - rail, hi[1], lo[2] + rail)),
        board((lo[0] + rail, lo[1], hi[2] - rail), (hi[0] - rail, hi[1], hi[2])),
    ]
    return join([board(thin, hi)] + rails)


def drawer_box(lo: np.ndarray, hi: np.ndarray, wall: float) -> trimesh.Trimesh:
    """An open-top tray spanning ``lo``..``hi``: a bottom and four walls, ``wall`` thick."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return join(
        [
            board((x0, y0, z0), (x1, y1, z0 + wall)),
            board((x0, y0, z0), (x0 + wall, y1, z1)),
            board((x1 - wall, y0, z0), (x1, y1, z1)),
            board((x0, y1 - wall, z0), (x1, y1, z1)),
            board((x0, y0, z0), (x1, y0 + wall, z1)),
        ]
    )


def bar_handle(length: float, radius: float, standoff: float, vertical: bool) -> trimesh.Trimesh:
    """A bar on two posts, in front of the origin (the posts grow from y = 0 towards -y).

    Args:
        length: bar length; the posts sit 0.8 of it apart.
        radius: bar radius (the posts are 0.8 of it).
        standoff: distance from the front face to the bar's axis.
        vertical: bar along z (doors) or along x (drawers).
    """
    bar = revolve(np.array([[radius, -length / 2], [radius, length / 2]]), segments=20)
    post = revolve(np.array([[0.8 * radius, 0.0], [0.8 * radius, standoff]]), segments=16)
    post = placed(post, rotation((1.0, 0.0, 0.0), np.pi / 2))  # along -y
    ends = [placed(post, translation((0.0, 0.0, s * 0.4 * length))) for s in (-1, 1)]
    handle = join([placed(bar, translation((0.0, -standoff, 0.0)))] + ends)
    return handle if vertical else placed(handle, rotation((0.0, 1.0, 0.0), np.pi / 2))


def knob(radius: float, standoff: float) -> trimesh.Trimesh:
    """A mushroom knob: a stem from y = 0 towards -y and a flattened ball ``radius`` wide at its end."""
    stem = revolve(np.array([[0.4 * radius, 0.0], [0.3 * radius, standoff]]), segments=20)
    stem = placed(stem, rotation((1.0, 0.0, 0.0), np.pi / 2))
    head = placed(ellipsoid((radius, 0.6 * radius, radius)), translation((0.0, -standoff, 0.0)))
    return join([stem, head])


def hinge_transform(hinge: tuple[float, float], angle: float) -> np.ndarray:
    """(4, 4) rotation by ``angle`` about the vertical axis through ``hinge`` = (x, y)."""
    h = np.array([hinge[0], hinge[1], 0.0])
    return translation(h) @ rotation((0.0, 0.0, 1.0), angle) @ translation(-h)


def slide_transform(distance: float) -> np.ndarray:
    """(4, 4) translation by ``distance`` out of the front (along -y)."""
    return translation((0.0, -distance, 0.0))
