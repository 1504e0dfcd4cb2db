"""Test-time tuning of the decoder's weights to the input view (issue 12): a probe, scored by ``affnerf eval``.

``affnerf-fit`` (what ``predict`` does) fits the codes and the camera to the photo and leaves the decoder's weights
alone; ``code_oracle.md`` found the decoder itself the ceiling (codes fitted to ten posed views reach about 0.66
mIoU). This asks whether one view can lift it: after the code fit, ``affnerf-tune`` also fits some of the fine
field's weights to the same crop, with the fitted codes and camera held, the same loss as the code fit (colour,
mask, and the encoder's own labels at the pixels and at points of the object, so the fit reshapes rather than
relabels) and an L2 prior pulling the weights back to the trained ones (relative to each tensor's own size). The
tuned copy renders and meshes that object only; the next object starts from the trained weights again.

Run (val40 protocol; one method per process so both can run side by side)::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/test_time_tuning.py --data DATA --out OUT --tune heads \
        --steps 30 --lr 3e-3 --prior 1.0
"""

from __future__ import annotations

import argparse
import copy

import numpy as np
import torch

from affnerf.cli.main import main as cli_main
from affnerf.eval.methods.affnerf import load_run
from affnerf.eval.methods.affnerf_fit import FittedAffNeRFMethod
from affnerf.eval.registry import MethodContext, MethodSpec, register_method
from affnerf.model.affnerf import Codes
from affnerf.predict.invert import (
    crop_loss,
    dataset_crop_target,
    draw_rays,
    object_points,
    point_labels,
    render_crop,
    target_tensors,
)

#: which of the fine field's parameters are tuned
GROUPS = {
    "heads": ("feature", "affordance", "color", "density"),
    "surface": ("color", "density"),
    "color": ("color",),
}


def tuned_parameters(field: torch.nn.Module, group: str) -> list[torch.nn.Parameter]:
    """The parameters of ``field`` whose names start with one of ``GROUPS[group]``."""
    return [p for n, p in field.named_parameters() if any(n.startswith(g) for g in GROUPS[group])]


def tune_weights(model, codes: Codes, target, camera, background, args) -> None:
    """Adam on the chosen weights of ``model`` (in place) against the crop, codes and camera held."""
    device = next(model.parameters()).device
    params = tuned_parameters(model.renderer.fine_field(), args.tune)
    start = [p.detach().clone() for p in params]
    scales = [float(p.pow(2).mean().sqrt().clamp_min(1e-6)) for p in start]
    pixels, rgb, mask, k = target_tensors(target, args.resolution, device)
    bg = torch.as_tensor(np.asarray(background), dtype=torch.float32, device=device)
    cam = torch.tensor(np.asarray(camera), dtype=torch.float32, device=device)
    with torch.no_grad():
        reference = [s.affordance for s in render_crop(model, codes, cam, pixels, k, bg)]
        points = object_points(model, codes, 32, model.config.occupancy_density)
        rng = np.random.default_rng(0)
        anchor = torch.from_numpy(points[rng.permutation(len(points))[:256]]).float().to(device)
        anchor_ref = point_labels(model, codes, anchor).softmax(-1) if len(anchor) else None
    for p in model.parameters():
        p.requires_grad_(False)
    for p in params:
        p.requires_grad_(True)
    optim = torch.optim.Adam(params, lr=args.lr)
    generator = torch.Generator().manual_seed(0)
    for _ in range(args.steps):
        pick = draw_rays(len(pixels), args.rays, generator).to(device)
        stages = render_crop(model, codes, cam, pixels[pick], k, bg)
        loss = crop_loss(stages, rgb[pick], mask[pick], 1.0, [r[pick] for r in reference], 1.0)
        if anchor_ref is not None:
            loss = loss - (anchor_ref * point_labels(model, codes, anchor).log_softmax(-1)).sum(-1).mean()
        drift = sum(((p - s) / c).pow(2).mean() for p, s, c in zip(params, start, scales, strict=True))
        loss = loss + args.prior * drift
        optim.zero_grad(set_to_none=True)
        loss.backward()
        optim.step()
    for p in model.parameters():
        p.requires_grad_(False)


class TunedAffNeRFMethod(FittedAffNeRFMethod):
    """``affnerf-fit``, then the decoder's chosen weights tuned to the input view (one view only)."""

    def __init__(self, *a, args: argparse.Namespace, **kw) -> None:
        super().__init__(*a, **kw)
        self.name = "affnerf-tune"
        self.args = args
        self.trained = copy.deepcopy(self.loaded.model.state_dict())

    def encode(self, obj, inputs):
        self.loaded.model.load_state_dict(self.trained)
        codes = super().encode(obj, inputs)
        if len(inputs) == 1 and self.args.steps > 0:
            target = dataset_crop_target(obj, inputs[0], self.loaded.model.config.encoder_resolution)
            camera = np.asarray(self.results[0].camera)
            with torch.enable_grad():
                tune_weights(self.loaded.model, codes, target, camera, self.loaded.background, self.args)
        return codes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--run", default="src/affnerf/weights/affnerf-small.pt")
    parser.add_argument("--tune", choices=sorted(GROUPS), default="heads")
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--lr", type=float, default=3e-3)
    parser.add_argument("--prior", type=float, default=1.0)
    parser.add_argument("--rays", type=int, default=512)
    parser.add_argument("--resolution", type=int, default=64)
    parser.add_argument("--split", default="val")
    parser.add_argument("--max-objects", default="5")
    args = parser.parse_args()

    def build(context: MethodContext) -> TunedAffNeRFMethod:
        loaded = load_run(context, "affnerf", "affnerf-tune")
        return TunedAffNeRFMethod(loaded, context.chunk, context.fast, context.mesh_resolution, args=args)

    register_method(MethodSpec("affnerf-tune", build, "affnerf-fit, then the decoder tuned to the view", False))
    method = "affnerf-tune" if args.steps > 0 else "affnerf-fit"
    cli_main(
        ["eval", "--run", args.run, "--data", args.data, "--split", args.split, "--method", method,
         "--scale", "0.25", "--target-views", "5", "--max-objects", args.max_objects, "--mesh-resolution", "96",
         "--device", "cpu", "--out", args.out]
    )  # fmt: skip


if __name__ == "__main__":
    main()
