"""``affnerf predict``: one photo -> turntable, labelled mesh (PLY and GLB) and a summary."""

from __future__ import annotations

import json
from dataclasses import replace
from typing import Annotated

import tyro

from affnerf.predict.outputs import PredictConfig


def predict(config: Annotated[PredictConfig, tyro.conf.arg(name="")]) -> None:
    """Predict a 3D affordance model from one image.

    The object is separated from its background (the image's alpha, --mask, or a uniform background), cropped,
    centred and resized the way training saw objects. Writes OUT/input.png, OUT/turntable/*.png and
    OUT/turntable.gif (RGB | affordance overlay), OUT/affordance_model.ply (vertex colours and an integer vertex
    property `affordance`), OUT/affordance_model.glb and OUT/prediction.json. Without --run, the model shipped
    with affnerf is used.
    """
    from affnerf.predict.outputs import write_prediction
    from affnerf.predict.predictor import Predictor
    from affnerf.predict.shipped import shipped_model

    run = config.run if config.run is not None else shipped_model()
    summary = write_prediction(Predictor.load(run, config.device, config.chunk, fast=config.fast, grid_threshold=config.grid_threshold), replace(config, run=run))
    print(json.dumps({k: summary[k] for k in ("classes_present", "surface_area_m2")}, indent=1))
    print(f"-> {config.out}")
