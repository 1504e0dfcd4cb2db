"""The constant-class guess: every pixel one class (background by default). The floor any method must clear."""

from __future__ import annotations

import numpy as np

from affnerf.data.dataset import ObjectData
from affnerf.eval.protocol import Prediction, TargetSet
from affnerf.eval.registry import MethodContext, MethodSpec, register_method


class ConstantMethod:
    """Predicts ``class_id`` everywhere and no colour."""

    def __init__(self, class_id: int = 0) -> None:
        self.class_id = class_id
        self.name = "constant" if class_id == 0 else f"constant-{class_id}"

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        shape = (len(targets.poses), targets.intrinsics.height, targets.intrinsics.width)
        return Prediction(np.full(shape, self.class_id, np.uint8))


def _build(context: MethodContext) -> ConstantMethod:
    return ConstantMethod(0)


register_method(MethodSpec("constant", _build, "background everywhere: the floor any method must clear", in_all=False))
