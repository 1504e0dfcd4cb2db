"""An exponential moving average of a model's weights, kept beside them during training (``--optim.ema-decay``).

Averaging the iterates of the last few thousand steps smooths out the noise of single steps (Polyak averaging;
diffusion models and many image networks are evaluated with such an average). The average is updated after every
optimiser step; a checkpoint holds it as ``ema`` beside the trained weights (``model``), and loading a model for
inference or as the start of another run takes the average when there is one
(:func:`affnerf.train.checkpoint.inference_weights`).
"""

from __future__ import annotations

import torch


def ema_rate(decay: float, updates: int) -> float:
    """The share of the current weights taken into the average at its ``updates``-th update (1-based): ``1 -
    decay``, but larger at the start (the decay is capped at ``(1 + n) / (10 + n)``, as TensorFlow's
    ExponentialMovingAverage does), so the first updates do not keep the random initial weights for thousands of
    steps.

    Example:
        >>> round(ema_rate(0.999, 1), 3), round(ema_rate(0.999, 10_000), 3)
        (0.818, 0.001)
    """
    n = max(updates, 1)
    return 1.0 - min(decay, (1.0 + n) / (10.0 + n))


class WeightAverage:
    """The average of a model's parameters; its buffers (batch-norm statistics) are taken as they are.

    Args:
        model: the model being trained.
        decay: the average's decay per step, in (0, 1).
    """

    def __init__(self, model: torch.nn.Module, decay: float) -> None:
        if not 0.0 < decay < 1.0:
            raise ValueError(f"an average of the weights needs a decay in (0, 1), not {decay}")
        self.decay = decay
        self.updates = 0
        self.names = [name for name, _ in model.named_parameters()]
        self.average = [p.detach().clone() for p in model.parameters()]

    @torch.no_grad()
    def reset(self, model: torch.nn.Module) -> None:
        """Start the average again from ``model``'s current parameters."""
        self.updates = 0
        torch._foreach_copy_(self.average, [p.detach() for p in model.parameters()])

    @torch.no_grad()
    def update(self, model: torch.nn.Module) -> None:
        """Move the average towards ``model``'s current parameters (one fused update over all of them)."""
        self.updates += 1
        current = [p.detach() for p in model.parameters()]
        torch._foreach_lerp_(self.average, current, ema_rate(self.decay, self.updates))

    def state_dict(self, model: torch.nn.Module) -> dict[str, torch.Tensor]:
        """``model``'s state dict with the averaged parameters in place of its own (loadable into the model)."""
        averaged = dict(zip(self.names, self.average, strict=True))
        return {k: averaged.get(k, v).detach().clone() for k, v in model.state_dict().items()}

    def load_state_dict(self, state: dict[str, torch.Tensor], updates: int) -> None:
        """Restore the average written by :meth:`state_dict` after ``updates`` updates."""
        with torch.no_grad():
            for name, value in zip(self.names, self.average, strict=True):
                value.copy_(state[name])
        self.updates = updates
