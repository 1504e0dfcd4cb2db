"""Two trained models predicting together (issue 12; benchmarks/results/ensemble.md): a deep ensemble
(Lakshminarayanan et al. 2017) of the shipped weights and other weights (the weights shipped before them; the
termination + Lovász candidate), scored on val40 or, with ``--protocol test64``, on the 64 test objects.

    .venv/bin/python benchmarks/ensemble.py [--protocol test64] --data DATA --out OUT.json CHECKPOINT CHECKPOINT [...]

Each member encodes the input view itself. At every sample point the members' colours are averaged and their
affordance distributions are averaged (the ensemble's logits are the log of the mean probabilities, so the
renderer's softmax gives that mean back). Density is combined two ways, each scored: ``density`` averages the
members' densities; ``distance`` averages their signed distances and takes the Laplace density of the mean at the
members' mean scale (the members must be signed-distance fields). Sample positions are shared: the ensemble's
coarse stage places the fine samples, as one model's would. Meshes use the first member's level.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path

import torch
from torch import nn

from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.registry import MethodSpec, register_method
from affnerf.eval.runner import EvalConfig, run_eval
from affnerf.model.base import ConditionedNeRF
from affnerf.model.field import ConditionalField, FieldOutput, PointGeometry, laplace_density
from affnerf.model.raymarch import Condition, FieldRenderer
from affnerf.predict.loading import LoadedModel, load_model

#: Config fields the members must share: they decide where samples go.
SHARED_FIELDS = ("scene_half_extent", "near", "far", "num_coarse", "num_fine", "clip_to_cube", "geometry")


def mean_log_probabilities(logits: Sequence[torch.Tensor]) -> torch.Tensor:
    """(..., K) log of the mean of the softmaxes of K-class logits, one tensor per member.

    Example:
        >>> a, b = torch.tensor([[0.0, 0.0]]), torch.tensor([[math.log(3.0), 0.0]])
        >>> torch.softmax(mean_log_probabilities([a, b]), dim=-1).tolist()
        [[0.625, 0.375]]
    """
    stacked = torch.stack([torch.log_softmax(x, dim=-1) for x in logits])
    return torch.logsumexp(stacked, dim=0) - math.log(len(logits))


class EnsembleField(nn.Module):
    """The members' fields of one stage as one field; it takes a tuple of per-member conditionings wherever a
    :class:`ConditionalField` takes one. ``combine``: ``density`` or ``distance`` (module docstring)."""

    def __init__(self, fields: Sequence[ConditionalField], combine: str) -> None:
        super().__init__()
        self.members = nn.ModuleList(fields)
        self.combine = combine

    def _density(self, densities: list, distances: list) -> torch.Tensor:
        if self.combine == "density":
            return torch.stack(densities).mean(0)
        beta = torch.stack([f.beta() for f in self.members]).mean()
        return laplace_density(torch.stack(distances).mean(0), beta)

    def forward(self, points, dirs, shape_codes: tuple, appearance_codes: tuple) -> FieldOutput:
        outs = [f(points, dirs, s, a) for f, s, a in zip(self.members, shape_codes, appearance_codes, strict=True)]
        sigma = self._density([o.sigma for o in outs], [o.distance for o in outs])
        rgb = torch.stack([o.rgb for o in outs]).mean(0)
        return FieldOutput(sigma=sigma, rgb=rgb, logits=mean_log_probabilities([o.logits for o in outs]))

    def supervised(self, points, shape_codes: tuple) -> PointGeometry:
        outs = [f.supervised(points, s) for f, s in zip(self.members, shape_codes, strict=True)]
        density = self._density([o.density for o in outs], [o.distance for o in outs])
        return PointGeometry(density, mean_log_probabilities([o.logits for o in outs]))

    def geometry(self, points, shape_codes: tuple) -> tuple[torch.Tensor, torch.Tensor]:
        out = self.supervised(points, shape_codes)
        return out.density, out.logits

    def density_only(self, points, shape_codes: tuple) -> torch.Tensor:
        return self.supervised(points, shape_codes).density


class EnsembleNeRF(ConditionedNeRF):
    """Trained models that render and mesh as one (config: the first member's)."""

    needs_input_pose = False

    def __init__(self, members: Sequence[ConditionedNeRF], combine: str) -> None:
        for name in SHARED_FIELDS:
            if len({getattr(m.config, name) for m in members}) > 1:
                raise SystemExit(f"the ensemble's models differ in {name}: they must share it")
        super().__init__(members[0].config, members[0].num_classes)
        self.members = nn.ModuleList(members)
        renderer = FieldRenderer.__new__(FieldRenderer)
        nn.Module.__init__(renderer)
        renderer.config, renderer.points_evaluated = self.config, 0
        renderer.coarse = EnsembleField([m.coarse for m in members], combine)
        renderer.fine = None if members[0].fine is None else EnsembleField([m.fine for m in members], combine)
        self.renderer = renderer

    def encode_views(self, images, intrinsics, poses) -> list:
        return [m.encode_views(images, intrinsics, poses) for m in self.members]

    def condition(self, encoding: list, ray_object: torch.Tensor) -> Condition:
        conds = [m.condition(e, ray_object) for m, e in zip(self.members, encoding, strict=True)]

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[tuple, tuple]:
            pairs = [c(points, rays) for c in conds]
            return tuple(p[0] for p in pairs), tuple(p[1] for p in pairs)

        return cond


#: side_by_side.sh's protocols: (split, objects per category).
PROTOCOLS = {"val40": ("val", 5), "test64": ("test", 8)}


def score(data: Path, out: Path, loaded: list[LoadedModel], combine: str, protocol: str = "val40") -> dict:
    """The ensemble's metrics on ``protocol`` (val40 or test64, ``side_by_side.sh``'s), written under ``out``."""
    split, objects = PROTOCOLS[protocol]

    def build(context):
        first = loaded[0]
        model = EnsembleNeRF([m.model for m in loaded], combine).eval()
        method = ConditionedNeRFMethod(
            LoadedModel(model, first.classes, first.step, first.path, first.train_config, first.background),
            context.chunk,
            context.fast,
            context.mesh_resolution,
        )
        method.name = f"ensemble-{combine}"
        return method

    register_method(MethodSpec(f"ensemble-{combine}", build, "an ensemble of trained models"))
    config = EvalConfig(
        run=loaded[0].path, data=data, out=out, split=split, method=f"ensemble-{combine}", scale=0.25,
        target_views=5, max_objects=objects, mesh_resolution=96, device="cpu",
    )  # fmt: skip
    return run_eval(config)[f"ensemble-{combine}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--work", type=Path, default=None, help="scratch folder (default: /tmp/affnerf-ensemble/PROTOCOL)"
    )
    parser.add_argument("--protocol", choices=sorted(PROTOCOLS), default="val40")
    parser.add_argument("models", type=Path, nargs="+")
    args = parser.parse_args()
    work = args.work or Path("/tmp/affnerf-ensemble") / args.protocol
    loaded = [load_model(m, "cpu") for m in args.models]
    results = {"models": [str(m) for m in args.models], "protocol": args.protocol}
    for combine in ("density", "distance"):
        started = time.perf_counter()
        metrics = score(args.data, work / combine, loaded, combine, args.protocol)
        results[combine] = {"mean": metrics["mean"], "categories": metrics["categories"]}
        results[combine]["seconds"] = round(time.perf_counter() - started, 1)
        print(combine, {k: round(v, 4) for k, v in metrics["mean"].items() if isinstance(v, float)})
    args.out.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
