"""The conditional radiance field of AFF-NeRF.

F_xyz: (PE(x, y, z), shape code) -> (density, affordance logits, feature q); F_dir: (PE(direction), appearance
code, q) -> colour. The affordance head reads q before the view direction enters (as Semantic-NeRF's semantic
head does), so affordance is a property of the point, not of the viewpoint.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import torch
from torch import nn

from affnerf.model.encoding import encoding_dim, positional_encoding


@dataclass(frozen=True)
class ObjectCodes:
    """Codes shared by all points of an object, kept factored: point i's code is ``table[object of i]``.

    A layer that concatenates a code to per-point inputs multiplies the code's columns of its weight with the same
    code for every point of an object; factored, :func:`linear_with_code` does that product once per object and
    picks the result per point, which makes the code's size nearly free (conditioning on concatenated global codes,
    the AFF-NeRF field). Per-point features that differ between points (pixel-aligned ones) stay plain tensors.

    Attributes:
        table: (B, D) one code per object.
        pick: (N, B) one-hot rows: the object of each point (a product rather than indexing keeps the gradient's
            summation order fixed, see :meth:`affnerf.model.affnerf.AffNeRF.condition`).
    """

    table: torch.Tensor
    pick: torch.Tensor

    def __len__(self) -> int:
        return self.pick.shape[0]

    def per_point(self) -> torch.Tensor:
        """(N, D) the code of every point."""
        return self.pick @ self.table

    def apply(self, fn: Callable[[torch.Tensor], torch.Tensor]) -> torch.Tensor:
        """(N, ...) ``fn`` of each point's code, computed once per object."""
        return self.pick @ fn(self.table)


Code = torch.Tensor | ObjectCodes


def linear_with_code(layer: nn.Linear, x: torch.Tensor, code: Code) -> torch.Tensor:
    """``layer(cat([x, code], -1))`` for (N, Dx) inputs and (N, D) codes; an :class:`ObjectCodes` code's product
    with its weight columns is computed once per object.

    Example:
        >>> layer = nn.Linear(3, 2); x = torch.randn(4, 1); table = torch.randn(2, 2)
        >>> pick = torch.nn.functional.one_hot(torch.tensor([0, 1, 1, 0]), 2).float()
        >>> codes = ObjectCodes(table, pick)
        >>> torch.allclose(linear_with_code(layer, x, codes), linear_with_code(layer, x, codes.per_point()))
        True
    """
    if not isinstance(code, ObjectCodes):
        return layer(torch.cat([x, code], dim=-1))
    d = code.table.shape[-1]
    if d == 0:
        return layer(x)
    w = layer.weight
    return nn.functional.linear(x, w[:, :-d]) + code.apply(lambda t: nn.functional.linear(t, w[:, -d:], layer.bias))


def per_object(
    point_object: torch.Tensor,
    points: torch.Tensor,
    width: int,
    fn: Callable[[int, torch.Tensor], torch.Tensor],
) -> torch.Tensor:
    """(N, width): ``fn(b, points of object b)`` -> (N_b, width) for each object b among the (N,) ``point_object``,
    placed back in the points' order."""
    out = points.new_zeros(len(points), width)
    for b in torch.unique(point_object).tolist():
        sel = point_object == b
        out[sel] = fn(b, points[sel])
    return out


#: A signed-distance field starts this far outside every point (metres), so a fresh field is nearly empty.
SDF_START = 0.02
#: Starting value of a signed-distance field's Laplace scale beta (metres); it is learnt.
SDF_BETA_INIT = 0.01
#: Beta never goes below this (metres): at 1 mm an object's inside reaches a density of 1,000 per metre.
SDF_BETA_MIN = 0.001


def laplace_density(distance: torch.Tensor, beta: torch.Tensor | float) -> torch.Tensor:
    """VolSDF's density of a signed distance: Psi_beta(-d) / beta, Psi_beta the CDF of a zero-mean Laplace
    distribution of scale beta. (N,) distances (metres, negative inside) -> (N,) densities (per metre): 0.5 / beta
    on the surface, rising to 1 / beta inside and falling as exp(-d / beta) outside.

    Example:
        >>> [round(v, 3) for v in laplace_density(torch.tensor([-1.0, 0.0, 0.01, 1.0]), 0.01).tolist()]
        [100.0, 50.0, 18.394, 0.0]
    """
    half = 0.5 * torch.exp(-distance.abs() / beta)
    return torch.where(distance > 0, half, 1.0 - half) / beta


@dataclass(frozen=True)
class FieldOutput:
    """Field values at sample points.

    Attributes:
        sigma: (..., ) non-negative density.
        rgb: (..., 3) colour in [0, 1].
        logits: (..., C - 1) affordance logits over the object classes (class 0, background, is rendered from
            transmittance, see :func:`affnerf.rendering.volume.render_affordance`).
        distance: (..., ) signed distance (metres) the density comes from, for a signed-distance field; else None.
    """

    sigma: torch.Tensor
    rgb: torch.Tensor
    logits: torch.Tensor
    distance: torch.Tensor | None = None


class PointGeometry(NamedTuple):
    """A field's geometry at supervision points.

    Attributes:
        density: (N,) density; logits: (N, C - 1) affordance logits; distance: (N,) signed distance (metres) of a
            signed-distance field, else None.
    """

    density: torch.Tensor
    logits: torch.Tensor
    distance: torch.Tensor | None = None


class ConditionalField(nn.Module):
    """An MLP field conditioned on a shape code and an appearance code.

    Args:
        num_classes: affordance classes including background (the dataset's ``affordance_classes``).
        code_dim: size of each code.
        width: hidden width of the position trunk.
        depth: number of trunk layers; the input is concatenated again after layer ``depth // 2`` (NeRF's skip).
        color_width: hidden width of the colour head.
        affordance_width: hidden width of the affordance head.
        pe_xyz: positional-encoding frequencies of positions.
        pe_dir: positional-encoding frequencies of view directions.
        color_code_dim: size of the conditioning the colour head takes (default: ``code_dim``).
        film: also modulate every trunk layer by the code (FiLM: ``relu(W h * (1 + gamma) + beta)``, gamma and beta
            linear in the code, as Occupancy Networks' conditional-normalisation decoder); the modulation starts
            at zero, so a fresh FiLM field computes what the concatenating one does.
        sdf: the density head gives a signed distance d (metres, negative inside; starting at :data:`SDF_START`
            everywhere) and the density is :func:`laplace_density` of it with a learnt scale beta (VolSDF); False:
            the density is a softplus of the head (the paper).
    """

    def __init__(
        self,
        num_classes: int,
        code_dim: int = 32,
        width: int = 256,
        depth: int = 8,
        color_width: int = 128,
        affordance_width: int = 128,
        pe_xyz: int = 10,
        pe_dir: int = 4,
        color_code_dim: int | None = None,
        film: bool = False,
        sdf: bool = False,
    ) -> None:
        super().__init__()
        color_code_dim = code_dim if color_code_dim is None else color_code_dim
        self.pe_xyz, self.pe_dir = pe_xyz, pe_dir
        in_dim = encoding_dim(3, pe_xyz) + code_dim
        self.skip = depth // 2
        layers = []
        for i in range(depth):
            d_in = in_dim if i == 0 else width + (in_dim if i == self.skip else 0)
            layers.append(nn.Linear(d_in, width))
        self.trunk_layers = nn.ModuleList(layers)
        self.width = width
        self.film: nn.Linear | None = None
        if film:
            self.film = nn.Linear(code_dim, 2 * width * depth)
            nn.init.zeros_(self.film.weight)
            nn.init.zeros_(self.film.bias)
        self.density = nn.Linear(width, 1)
        self.log_beta: nn.Parameter | None = None
        if sdf:
            self.log_beta = nn.Parameter(torch.tensor(math.log(SDF_BETA_INIT)))
            nn.init.zeros_(self.density.weight)
            nn.init.zeros_(self.density.bias)
        self.feature = nn.Linear(width, width)
        self.affordance = nn.Sequential(
            nn.Linear(width, affordance_width), nn.ReLU(), nn.Linear(affordance_width, num_classes - 1)
        )
        self.color = nn.Sequential(
            nn.Linear(width + encoding_dim(3, pe_dir) + color_code_dim, color_width),
            nn.ReLU(),
            nn.Linear(color_width, 3),
        )

    def trunk(self, points: torch.Tensor, shape_code: Code) -> torch.Tensor:
        """(N, width) trunk features of (N, 3) points under (N, code_dim) shape codes (a tensor or factored)."""
        pe = positional_encoding(points, self.pe_xyz)
        mods = None
        if self.film is not None:  # (N, depth, 2, width): each layer's gamma and beta
            film = self.film
            mods = shape_code.apply(film) if isinstance(shape_code, ObjectCodes) else film(shape_code)
            mods = mods.reshape(len(points), len(self.trunk_layers), 2, self.width)
        h = pe
        for i, layer in enumerate(self.trunk_layers):
            if i == 0:
                h = linear_with_code(layer, pe, shape_code)
            elif i == self.skip:  # the input again: [h, PE(x), code]
                h = linear_with_code(layer, torch.cat([h, pe], dim=-1), shape_code)
            else:
                h = layer(h)
            if mods is not None:
                h = h * (1.0 + mods[:, i, 0]) + mods[:, i, 1]
            h = torch.relu(h)
        return h

    def beta(self) -> torch.Tensor | None:
        """The Laplace scale of a signed-distance field (0-d, metres), or None."""
        return None if self.log_beta is None else self.log_beta.exp().clamp(min=SDF_BETA_MIN)

    def density_and_distance(self, h: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor | None]:
        """(N,) non-negative density from trunk features, with the (N,) signed distance (metres) it comes from, from
        one pass of the head: :func:`laplace_density` of the distance for a signed-distance field; else a softplus
        of the head, shifted so a fresh field starts nearly empty, and None."""
        raw = self.density(h)[..., 0]
        beta = self.beta()
        if beta is None:
            return nn.functional.softplus(raw - 1.0), None
        distance = raw + SDF_START
        return laplace_density(distance, beta), distance

    def density_from(self, h: torch.Tensor) -> torch.Tensor:
        """(N,) non-negative density from trunk features (:meth:`density_and_distance`)."""
        return self.density_and_distance(h)[0]

    def forward(self, points: torch.Tensor, dirs: torch.Tensor, shape_code: Code, appearance_code: Code) -> FieldOutput:
        """Evaluate the field.

        Args:
            points: (N, 3) positions in the canonical frame.
            dirs: (N, 3) unit view directions.
            shape_code: (N, code_dim) shape code of each point's object (a tensor or :class:`ObjectCodes`).
            appearance_code: (N, code_dim) appearance code of each point's object (likewise).
        """
        h = self.trunk(points, shape_code)
        q = self.feature(h)
        view = torch.cat([q, positional_encoding(dirs, self.pe_dir)], dim=-1)
        hidden = linear_with_code(self.color[0], view, appearance_code)
        rgb = torch.sigmoid(self.color[2](torch.relu(hidden)))
        sigma, distance = self.density_and_distance(h)
        return FieldOutput(sigma=sigma, rgb=rgb, logits=self.affordance(q), distance=distance)

    def density_only(self, points: torch.Tensor, shape_code: Code) -> torch.Tensor:
        """(N,) density alone, for mesh extraction and occupancy grids."""
        return self.density_from(self.trunk(points, shape_code))

    def geometry(self, points: torch.Tensor, shape_code: Code) -> tuple[torch.Tensor, torch.Tensor]:
        """(N,) density and (N, C - 1) affordance logits at points (no colour), for labelling meshes."""
        out = self.supervised(points, shape_code)
        return out.density, out.logits

    def supervised(self, points: torch.Tensor, shape_code: Code) -> PointGeometry:
        """What 3D supervision compares with its targets at (N, 3) points (:class:`PointGeometry`)."""
        h = self.trunk(points, shape_code)
        density, distance = self.density_and_distance(h)
        return PointGeometry(density, self.affordance(self.feature(h)), distance)
