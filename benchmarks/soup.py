"""A model soup (issue 12; benchmarks/results/model_soup.md): the weights of several further stages trained from the
same checkpoint, averaged into one model (Wortsman et al. 2022, "Model soups"). Stages fine-tuned from one starting
point tend to stay in one basin of the loss, where their average can beat each of them at no cost at inference.

    .venv/bin/python benchmarks/soup.py --out SOUP.pt RUN_OR_CHECKPOINT RUN_OR_CHECKPOINT [...]

Floating-point weights and buffers (batch-norm statistics included) are averaged with equal weights; integer
buffers (batch counts) and every other entry come from the first model. The soup must then be calibrated
(``affnerf eval calibrate --checkpoint SOUP.pt``) like any new model.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import torch

from affnerf.errors import AffnerfError
from affnerf.predict.loading import resolve_checkpoint
from affnerf.predict.shipped import INFERENCE_KEYS
from affnerf.train.checkpoint import load_checkpoint


def average_states(states: list[dict[str, torch.Tensor]]) -> dict[str, torch.Tensor]:
    """The entry-wise mean of state dicts with the same keys and shapes (integer entries: the first's).

    Example:
        >>> a = {"w": torch.tensor([1.0, 3.0]), "n": torch.tensor(4)}
        >>> b = {"w": torch.tensor([3.0, 5.0]), "n": torch.tensor(9)}
        >>> {k: v.tolist() for k, v in average_states([a, b]).items()}
        {'w': [2.0, 4.0], 'n': 4}
    """
    first = states[0]
    for other in states[1:]:
        if other.keys() != first.keys() or any(other[k].shape != first[k].shape for k in first):
            raise AffnerfError("the models to average have different architectures")
    return {
        key: torch.stack([s[key] for s in states]).mean(dim=0) if value.is_floating_point() else value.clone()
        for key, value in first.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("models", type=Path, nargs="+", help="run folders (their last checkpoint) or checkpoint files")
    args = parser.parse_args()
    data = [load_checkpoint(resolve_checkpoint(m)) for m in args.models]
    soup = {key: data[0][key] for key in INFERENCE_KEYS if key in data[0]}
    soup["model"] = average_states([d["model"] for d in data])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    torch.save(soup, args.out)
    print(f"{args.out}: the mean of {len(data)} models")


if __name__ == "__main__":
    main()
