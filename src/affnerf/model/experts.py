"""Weight experts: a trunk layer whose weights are a per-object mixture of E weight sets.

Beyond the paper. A decoder shared by every family must hold them all in one set of weights; the small preset's
64-wide trunk fails on cabinets and buckets even for its own training objects. Widening it costs every point of
every step (``benchmarks/results/capacity.md``). Here each layer keeps E weight sets and each object mixes them with
its own weights pi (from its shape code, :class:`Router`): ``W_b = sum_e pi_be W_e`` (conditionally parameterised
layers, CondConv). A point still costs one product with one (out, in) matrix, so E sets cost memory, not time. The
router is trained to pick the object's family (``loss/router``), so each set learns one family while an object
the router is unsure of (an unseen family) takes a blend.
"""

from __future__ import annotations

import torch
from torch import nn


class ExpertLinear(nn.Module):
    """``experts`` linear layers of the same shape, mixed per object.

    Args:
        in_features, out_features: as :class:`torch.nn.Linear`.
        experts: number of weight sets E; every set starts as the same draw of :class:`torch.nn.Linear`'s
            initialisation, so a fresh layer computes one linear layer whatever the mixture.

    Attributes:
        weight: (E, out, in); bias: (E, out).
    """

    def __init__(self, in_features: int, out_features: int, experts: int) -> None:
        super().__init__()
        base = nn.Linear(in_features, out_features)
        self.weight = nn.Parameter(base.weight.detach().clone().unsqueeze(0).repeat(experts, 1, 1))
        self.bias = nn.Parameter(base.bias.detach().clone().unsqueeze(0).repeat(experts, 1))

    def mixed(self, mix: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(B, E) mixture weights -> each object's (B, out, in) weight and (B, out) bias."""
        return torch.einsum("be,eoi->boi", mix, self.weight), mix @ self.bias


def grouped_linear(x: torch.Tensor, weight: torch.Tensor, counts: list[int]) -> torch.Tensor:
    """(N, in) rows grouped by object (the first ``counts[0]`` rows of object 0, then object 1's, ...) times their
    object's (B, out, in) ``weight`` -> (N, out); one batched product when every object has as many rows.

    Example:
        >>> w = torch.randn(2, 3, 4); x = torch.randn(5, 4)
        >>> y = grouped_linear(x, w, [2, 3])
        >>> torch.allclose(y[:2], x[:2] @ w[0].T) and torch.allclose(y[2:], x[2:] @ w[1].T)
        True
    """
    if not len(x):
        return x.new_zeros(0, weight.shape[1])
    if len(set(counts)) == 1:
        b = len(counts)
        return torch.bmm(x.reshape(b, counts[0], -1), weight.transpose(1, 2)).reshape(len(x), -1)
    return torch.cat([chunk @ weight[b].T for b, chunk in enumerate(torch.split(x, counts)) if len(chunk)])


def group_order(point_object: torch.Tensor, objects: int) -> tuple[torch.Tensor | None, list[int]]:
    """The permutation that groups (N,) object indices by object (None when they already are) and each object's
    row count (B,), for :func:`grouped_linear`."""
    counts = torch.bincount(point_object, minlength=objects).tolist()
    if len(point_object) < 2 or bool((point_object[1:] >= point_object[:-1]).all()):
        return None, counts
    return torch.argsort(point_object, stable=True), counts


class Router(nn.Module):
    """Each object's mixture of weight experts from its shape code: ``softmax(linear(code))``.

    Args:
        code_dim: size of the shape code; experts: E.
    """

    def __init__(self, code_dim: int, experts: int) -> None:
        super().__init__()
        self.linear = nn.Linear(code_dim, experts)

    def logits(self, codes: torch.Tensor) -> torch.Tensor:
        """(B, code_dim) -> (B, E) unnormalised scores."""
        return self.linear(codes)

    def forward(self, codes: torch.Tensor) -> torch.Tensor:
        """(B, code_dim) -> (B, E) mixture weights (each row sums to 1)."""
        return torch.softmax(self.logits(codes), dim=-1)
