"""Distil codes fitted to the training objects into the encoders (issue 12, results/distil_codes.md).

The code oracle (``code_oracle_shipped.md``) found the shipped decoder rendering new views at 0.785 validation mIoU
with codes fitted to posed views, against 0.670 from the encoder's one view: the encoder, above all on objects it
never saw, is the limit. This asks whether a cleaner target teaches it better than the rendering loss does. Four
modes, each from the shipped weights (or ``--checkpoint``) on the training objects of ``--data``, one thread:

- ``fit``: the decoder frozen, one shape and one appearance code per training object (a table, started from the
  mean of the encoder's codes over ``--init-views`` views) fitted by sparse Adam to the training loss of those
  objects' rays and 3D points (an auto-decoder, as DeepSDF fits its latents). Writes the table (``--codes``).
- ``distil``: the decoder frozen, the encoders trained to regress the table's codes from one random view of each
  object (squared error per dimension, over the table's spread in that dimension); no rendering. Writes a run
  folder with one checkpoint, which ``affnerf eval calibrate`` and ``affnerf eval`` score like any run.
- ``encoders``: the control, the same encoder-only stage with the training loss itself (rendered rays and points);
  with ``--distil-weight W`` and ``--codes``, the distillation term weighted W beside it.
- ``check``: the table's codes, the encoder's from one view and the table's starting codes rendered at the protocol's
  target views of ``--per-category`` training objects a category (mIoU a category, in OUT/record.json).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/distil_codes.py fit --data DATA --cache-dir CACHE \
        --steps 18500 --minutes 25 --codes W/codes.pt --out W/fit
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/distil_codes.py distil --data DATA --cache-dir CACHE \
        --steps 20000 --minutes 15 --lr 3e-4 --codes W/codes.pt --out W/distil
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/distil_codes.py encoders --data DATA --cache-dir CACHE \
        --steps 18900 --minutes 40 [--codes W/codes.pt --distil-weight 0.1] --out W/encoders

Each run folder is then calibrated and scored as any run (``benchmarks/side_by_side.sh``: ``calibrated_val40``,
``test64``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import time
from pathlib import Path

import numpy as np
import torch
from code_oracle import category_mious, target_labels  # a sibling script: benchmarks/ is on the path

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.metrics.segmentation import confusion_matrix
from affnerf.model.affnerf import Codes
from affnerf.predict.loading import load_model
from affnerf.train import distributed as dist_utils
from affnerf.train.checkpoint import load_checkpoint
from affnerf.train.config import TrainConfig, config_from_json
from affnerf.train.sampler import encoder_crops
from affnerf.train.schedule import learning_rate
from affnerf.train.trainer import Trainer

SHIPPED = Path("src/affnerf/weights/affnerf-small.pt")


class CodeTable(torch.nn.Module):
    """One shape and one appearance code per object id, each an embedding with sparse gradients."""

    def __init__(self, ids: list[str], shape: torch.Tensor, appearance: torch.Tensor) -> None:
        super().__init__()
        self.ids = list(ids)
        self.row = {object_id: i for i, object_id in enumerate(self.ids)}
        self.shape = torch.nn.Embedding.from_pretrained(shape.clone(), freeze=False, sparse=True)
        self.appearance = torch.nn.Embedding.from_pretrained(appearance.clone(), freeze=False, sparse=True)

    def forward(self, object_ids: list[str]) -> Codes:
        """The (B, D) codes of ``object_ids``."""
        rows = torch.tensor([self.row[i] for i in object_ids], dtype=torch.long)
        return Codes(self.shape(rows), self.appearance(rows))

    def payload(self) -> dict:
        return {"ids": self.ids, "shape": self.shape.weight.detach(), "appearance": self.appearance.weight.detach()}


def load_table(path: Path, prefix: str = "") -> tuple[CodeTable, Codes]:
    """The fitted table written by ``fit`` (frozen), or with ``prefix`` ``start_`` the codes it started from, and
    each code's (D,) spread over the table's objects."""
    saved = torch.load(path, weights_only=False)
    shape, appearance = saved[prefix + "shape"], saved[prefix + "appearance"]
    table = CodeTable(saved["ids"], shape, appearance).requires_grad_(False)
    return table, Codes(shape.std(0), appearance.std(0))


class TablePass(torch.nn.Module):
    """The trainer's forward pass with each object's codes read from the table instead of encoded."""

    def __init__(self, model: torch.nn.Module, table: CodeTable) -> None:
        super().__init__()
        self.model, self.table = model, table

    def forward(self, batch, generator, points=None, surface_share: float = 0.0):
        encoding = self.table(batch.object_ids)
        rays = (encoding, batch.ray_object, batch.origins, batch.dirs, batch.background, True, generator)
        coarse, fine = self.model.render_rays(*rays)
        geometry = None if points is None else self.model.point_geometry(encoding, points.point_object, points.points)
        return coarse, fine, geometry, {}


def stage_config(args: argparse.Namespace, lr: float, lr_final: float) -> TrainConfig:
    """The checkpoint's own training config, pointed at this run's data, cache, folder, steps and rates."""
    config = config_from_json(load_checkpoint(args.checkpoint)["train_config"], args.checkpoint)
    optim = dataclasses.replace(config.optim, lr=lr, lr_final=lr_final, grad_clip=0.0, ema_decay=0.0)
    return dataclasses.replace(
        config,
        data=args.data,
        out=args.out,
        cache_dir=args.cache_dir,
        steps=args.steps,
        init_from=args.checkpoint,
        optim=optim,
        resume=False,
        stop_at=0,
        time_limit=0.0,
        val_every=0,
        progress=False,
        checkpoint_every=args.steps,
        keep_checkpoints=1,
        seed=args.seed,
        device="cpu",
    )


def make_trainer(config: TrainConfig) -> Trainer:
    """A single-process trainer set up for ``config`` (its data cached, the checkpoint's weights loaded)."""
    trainer = Trainer(config, dist_utils.setup("cpu"))
    trainer.setup()
    return trainer


@torch.no_grad()
def encoder_codes(model: torch.nn.Module, frames: list, views: int, seed: int) -> Codes:
    """(N, D) codes of each object: the mean of the encoder's codes over ``views`` random views of it."""
    rng = np.random.default_rng(seed)
    shapes, appearances = [], []
    for obj in frames:
        enc = rng.choice(len(obj), views, replace=False)
        crops = torch.from_numpy(encoder_crops(obj, enc)).permute(0, 3, 1, 2).float() / 255.0
        codes = model.encode(crops)
        shapes.append(codes.shape.mean(0))
        appearances.append(codes.appearance.mean(0))
    return Codes(torch.stack(shapes), torch.stack(appearances))


def run_steps(trainer: Trainer, step_fn, steps: int, minutes: float) -> dict:
    """``step_fn(step)`` -> loss for ``steps`` steps or ``minutes``; the loss averaged over blocks of 500 steps."""
    start, losses, curve = time.perf_counter(), [], []
    done = 0
    for step in range(steps):
        losses.append(float(step_fn(step)))
        done = step + 1
        if done % 500 == 0:
            curve.append([done, float(np.mean(losses[-500:])), round(time.perf_counter() - start, 1)])
            print(f"step {done} loss {curve[-1][1]:.5f} {curve[-1][2]:.0f} s", flush=True)
        if minutes > 0 and time.perf_counter() - start > 60 * minutes:
            break
    trainer.step = done
    return {"steps": done, "seconds": round(time.perf_counter() - start, 1), "curve": curve}


def fit(args: argparse.Namespace) -> dict:
    """Fit the training objects' codes with the decoder frozen; writes ``--codes``."""
    trainer = make_trainer(stage_config(args, args.lr, args.lr_final))
    model = trainer.state.model
    model.requires_grad_(False)
    frames = trainer.state.sampler.objects
    start = encoder_codes(model, frames, args.init_views, args.seed)
    table = CodeTable([f.object_id for f in frames], start.shape, start.appearance)
    trainer.net = TablePass(model, table)
    trainer.state.optimizer = torch.optim.SparseAdam(list(table.parameters()), lr=args.lr)
    record = run_steps(trainer, training_loss(trainer), args.steps, args.minutes)
    args.codes.parent.mkdir(parents=True, exist_ok=True)
    torch.save({**table.payload(), "start_shape": start.shape, "start_appearance": start.appearance}, args.codes)
    return record


def training_loss(trainer: Trainer):
    """A step of ``trainer``'s own iteration (its batch, loss and optimiser), returning the step's total loss."""
    return lambda step: trainer.train_iteration(step)["loss/total"]


def code_gap(codes: Codes, target: Codes, spread: Codes) -> torch.Tensor:
    """Mean squared difference of (B, D) codes from their targets, each dimension over the table's (D,) spread."""
    shape = ((codes.shape - target.shape) / spread.shape).pow(2).mean()
    return (shape + ((codes.appearance - target.appearance) / spread.appearance).pow(2).mean()) / 2


def encoder_stage(args: argparse.Namespace) -> tuple[Trainer, torch.optim.Optimizer]:
    """A trainer from the checkpoint whose decoder is frozen and whose optimiser holds the encoders alone."""
    trainer = make_trainer(stage_config(args, args.lr, args.lr_final))
    model = trainer.state.model
    model.requires_grad_(False)
    encoders = [m for m in (model.shape_encoder, model.appearance_encoder) if m is not None]
    params = [p for m in encoders for p in m.parameters()]
    for p in params:
        p.requires_grad_(True)
    trainer.state.optimizer = torch.optim.Adam(params, lr=args.lr)
    return trainer, trainer.state.optimizer


def distil(args: argparse.Namespace) -> dict:
    """Train the encoders to regress the table's codes; the decoder frozen, nothing rendered."""
    trainer, optimizer = encoder_stage(args)
    model, sampler = trainer.state.model, trainer.state.sampler
    table, spread = load_table(args.codes)

    def step_fn(step: int) -> float:
        for group in optimizer.param_groups:
            group["lr"] = learning_rate(trainer.config, step)
        batch = sampler.next_batch()
        views = batch.images[:, :1]
        codes = model.encode_views(views, batch.input_intrinsics[:, :1], batch.input_poses[:, :1])
        loss = code_gap(codes, table(batch.object_ids), spread)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        optimizer.step()
        return loss.detach()

    record = run_steps(trainer, step_fn, args.steps, args.minutes)
    trainer.save_checkpoint(trainer.step)
    return record


def encoders_control(args: argparse.Namespace) -> dict:
    """The encoder-only stage with the training loss itself (the control of ``distil``); with
    ``--distil-weight`` w > 0, plus w times the distillation term towards the table's codes (``--codes``)."""
    trainer, _ = encoder_stage(args)
    if args.distil_weight > 0:
        add_distil_term(trainer, args.codes, args.distil_weight)
    record = run_steps(trainer, training_loss(trainer), args.steps, args.minutes)
    trainer.save_checkpoint(trainer.step)
    return record


def add_distil_term(trainer: Trainer, codes_path: Path, weight: float) -> None:
    """Make ``trainer``'s loss also pull the step's encoded codes towards the table's (``weight`` x
    :func:`code_gap`): the encoding is kept as the model makes it, and the loss reads it."""
    model = trainer.state.model
    table, spread = load_table(codes_path)
    kept: list[Codes] = []
    encode_views, loss = model.encode_views, trainer._loss

    def keeping(*inputs):
        kept[:] = [encode_views(*inputs)]
        return kept[0]

    def with_codes(batch, points, mu, share=0.0):
        total, parts = loss(batch, points, mu, share)
        gap = code_gap(kept[0], table(batch.object_ids), spread)
        parts["loss/distil"] = gap.detach()
        return total + weight * gap, parts

    model.encode_views = keeping
    trainer._loss = with_codes


def check(args: argparse.Namespace) -> dict:
    """The table's codes against the encoder's from the protocol's input view, rendered at the protocol's 5 target
    views (100x75) of ``--per-category`` training objects a category (as code_oracle.py scores): mIoU a category."""
    loaded = load_model(args.checkpoint, "cpu")
    loaded.model.eval()
    method, dataset = ConditionedNeRFMethod(loaded), Dataset.open(args.data)
    table, start = load_table(args.codes)[0], load_table(args.codes, "start_")[0]
    protocol, n = ProtocolConfig(target_views=5, scale=0.25), len(dataset.affordance_classes)
    conf: dict[str, dict[str, np.ndarray]] = {"encoder": {}, "table": {}, "table_start": {}}
    for entry in interleave_categories(dataset.objects("train"), args.per_category):
        obj = dataset.load_object(entry)
        inputs, targets = choose_views(len(obj), entry.id, protocol)
        with torch.no_grad():
            codes = {
                "encoder": method.encode(obj, inputs),
                "table": table([entry.id]),
                "table_start": start([entry.id]),
            }
        for name, c in codes.items():
            pred, gt = target_labels(method, c, obj, targets, protocol.scale)
            conf[name].setdefault(entry.category, np.zeros((n, n), np.int64))
            conf[name][entry.category] += confusion_matrix(gt, pred, n)
    result = {name: category_mious(cats) for name, cats in conf.items()}
    for name, scores in result.items():
        print(name, round(scores["mIoU"], 3), {c: round(v, 3) for c, v in scores["per_category"].items()}, flush=True)
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", choices=("fit", "distil", "encoders", "check"))
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--cache-dir", type=Path, required=True)
    parser.add_argument("--checkpoint", type=Path, default=SHIPPED)
    parser.add_argument("--out", type=Path, required=True, help="run folder (config, checkpoint, record.json)")
    parser.add_argument("--codes", type=Path, help="the fitted code table (written by fit, read by distil)")
    parser.add_argument("--steps", type=int, default=0, help="the schedule's length")
    parser.add_argument("--minutes", type=float, default=0.0, help="stop early after this many minutes")
    parser.add_argument("--lr", type=float, default=None, help="fit 0.02, distil and encoders 2e-4")
    parser.add_argument("--lr-final", type=float, default=None, help="a tenth of --lr")
    parser.add_argument("--init-views", type=int, default=8, help="fit: views whose codes start the table")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--distil-weight", type=float, default=0.0, help="encoders: weight of the distillation term")
    parser.add_argument("--per-category", type=int, default=2, help="check: training objects a category")
    args = parser.parse_args()
    if (args.mode in ("fit", "distil", "check") or args.distil_weight > 0) and args.codes is None:
        parser.error(f"{args.mode} needs --codes")
    args.lr = args.lr if args.lr is not None else (0.02 if args.mode == "fit" else 2e-4)
    args.lr_final = args.lr_final if args.lr_final is not None else args.lr / 10
    torch.set_num_threads(1)
    logging.basicConfig(level=logging.INFO)
    modes = {"fit": fit, "distil": distil, "encoders": encoders_control, "check": check}
    record = modes[args.mode](args)
    record["settings"] = {k: str(v) for k, v in vars(args).items()}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "record.json").write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
