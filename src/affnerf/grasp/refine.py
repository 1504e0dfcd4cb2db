"""Parallel gradient-based local search of grasps (in the spirit of DiPGrasp): all candidates at once in torch.

Each grasp is a centre, a closing axis, an approach direction and an opening. The energy pulls both pads onto
the surface (contact residual), turns the surface normals at the contacts against the pads (normal alignment),
keeps the closing line inside both friction cones (force-closure residual), keeps the axis near the object's
centroid (torque), pushes the object's surface out of the fingers and palm (collision barrier) and keeps the
opening within the gripper's limits. The surface is a dense sample of points with normals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from affnerf.grasp.gripper import ParallelJawGripper


@dataclass(frozen=True)
class RefineConfig:
    """Weights and schedule of the local search.

    Attributes:
        steps: gradient steps.
        lr: Adam learning rate (metres for the centre and opening; unitless for directions).
        mu: friction coefficient of the force-closure residual.
        contact: weight of the pads-on-surface residual (per squared metre).
        alignment: weight of the normal alignment.
        closure: weight of the force-closure residual.
        torque: weight of the centroid-to-axis distance (relative to the object radius).
        collision: weight of the collision barrier (per squared metre of penetration).
        margin: clearance the barrier asks for, metres.
        barrier_points: surface points the collision barrier checks (a subset of the sample).
    """

    steps: int = 40
    lr: float = 2e-3
    mu: float = 0.5
    contact: float = 2e4
    alignment: float = 1.0
    closure: float = 4.0
    torque: float = 0.5
    collision: float = 2e4
    margin: float = 0.002
    barrier_points: int = 600


def _box_sdf(points: torch.Tensor, centre: torch.Tensor, half: torch.Tensor) -> torch.Tensor:
    """Signed distance of points (..., 3) to axis-aligned boxes (centre, half extents) in the same frame."""
    q = (points - centre).abs() - half
    outside = q.clamp(min=0).norm(dim=-1)
    inside = q.max(dim=-1).values.clamp(max=0)
    return outside + inside


def _frames(axis: torch.Tensor, approach: torch.Tensor) -> torch.Tensor:
    """(G, 3, 3) rotations with columns x (closing axis), y, z (approach orthogonalised)."""
    x = torch.nn.functional.normalize(axis, dim=-1)
    z = approach - (approach * x).sum(-1, keepdim=True) * x
    z = torch.nn.functional.normalize(z, dim=-1)
    return torch.stack([x, torch.cross(z, x, dim=-1), z], dim=-1)


def grasp_energy(
    centre: torch.Tensor,
    axis: torch.Tensor,
    approach: torch.Tensor,
    width: torch.Tensor,
    surface: torch.Tensor,
    normals: torch.Tensor,
    centroid: torch.Tensor,
    radius: float,
    gripper: ParallelJawGripper,
    config: RefineConfig,
) -> torch.Tensor:
    """(G,) energy of G grasps on a surface sample (N, 3) with outward normals (N, 3)."""
    rot = _frames(axis, approach)
    x = rot[..., 0]
    pads = torch.stack([centre - 0.5 * width[:, None] * x, centre + 0.5 * width[:, None] * x], dim=1)  # (G, 2, 3)
    dist = torch.cdist(pads.reshape(-1, 3), surface)  # (2G, N)
    nearest = dist.argmin(dim=1)
    contact = dist.gather(1, nearest[:, None]).reshape(-1, 2).pow(2).sum(-1)
    n = normals[nearest].reshape(-1, 2, 3)
    cos1, cos2 = -(n[:, 0] * x).sum(-1), (n[:, 1] * x).sum(-1)  # 1 when each normal faces its pad
    alignment = (1 - cos1) ** 2 + (1 - cos2) ** 2
    cone = math.cos(math.atan(config.mu))
    closure = (cone - cos1).clamp(min=0) ** 2 + (cone - cos2).clamp(min=0) ** 2
    arm = torch.cross(centroid[None] - centre, x, dim=-1).norm(dim=-1) / radius
    sparse = surface[:: max(1, len(surface) // config.barrier_points)]
    local = torch.einsum("gji,gnj->gni", rot, sparse[None] - centre[:, None])  # surface in each grasp frame
    barrier = torch.zeros_like(contact)
    for k, (box_c, box_h) in enumerate(gripper.boxes(0.0)):
        c = torch.as_tensor(box_c, dtype=surface.dtype).expand(len(centre), 3).clone()
        half = torch.as_tensor(box_h, dtype=surface.dtype).expand(len(centre), 3).clone()
        if k < 2:  # fingers move with the opening; their inner faces sit at the pads
            c[:, 0] = (-1.0 if k == 0 else 1.0) * (0.5 * width + gripper.finger_thickness / 2.0)
        else:
            half[:, 0] = 0.5 * width + gripper.finger_thickness
        sdf = _box_sdf(local, c[:, None], half[:, None])
        # fingers may touch the surface (their pads must) but not cut into it; the palm keeps a clearance
        clearance = 0.0 if k < 2 else config.margin
        barrier = barrier + (clearance - sdf).clamp(min=0).pow(2).sum(-1)
    limits = (width - gripper.max_opening).clamp(min=0) ** 2 + (0.002 - width).clamp(min=0) ** 2
    return (
        config.contact * contact
        + config.alignment * alignment
        + config.closure * closure
        + config.torque * arm**2
        + config.collision * barrier
        + 1e4 * limits
    )


def refine_grasps(
    centres: np.ndarray,
    axes: np.ndarray,
    approaches: np.ndarray,
    widths: np.ndarray,
    surface: np.ndarray,
    normals: np.ndarray,
    centroid: np.ndarray,
    radius: float,
    gripper: ParallelJawGripper = ParallelJawGripper(),
    config: RefineConfig = RefineConfig(),
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Refine G grasps together by gradient descent on :func:`grasp_energy`.

    Returns:
        centres (G, 3), unit axes (G, 3), unit approaches orthogonal to them (G, 3), widths (G,).
    """
    as_t = lambda a: torch.as_tensor(np.asarray(a), dtype=torch.float32)  # noqa: E731
    params = [
        as_t(centres).clone().requires_grad_(),
        as_t(axes).clone().requires_grad_(),
        as_t(approaches).clone().requires_grad_(),
        as_t(widths).clone().requires_grad_(),
    ]
    surf, norm, cen = as_t(surface), as_t(normals), as_t(centroid)
    optimizer = torch.optim.Adam(params, lr=config.lr)
    for _ in range(config.steps):
        energy = grasp_energy(*params, surf, norm, cen, radius, gripper, config).sum()
        optimizer.zero_grad()
        energy.backward()
        optimizer.step()
    with torch.no_grad():
        rot = _frames(params[1], params[2])
    return (
        params[0].detach().numpy().astype(np.float64),
        rot[..., 0].numpy().astype(np.float64),
        rot[..., 2].numpy().astype(np.float64),
        params[3].detach().numpy().astype(np.float64),
    )
