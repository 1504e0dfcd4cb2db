"""``affnerf predict``: one photo -> turntable, labelled mesh (PLY and GLB) and a summary."""

from __future__ import annotations

import json
from dataclasses import replace
from typing import Annotated

import tyro

from affnerf.predict.outputs import PredictConfig


def predict(config: Annotated[PredictConfig, tyro.conf.arg(name="")]) -> None:
    """Predict a 3D affordance model from one image.

    The object is separated from its background (--mask, else --segment: by default the image's alpha, else a
    uniform background when the border is of one colour, else the object segmenter that ships with affnerf (or one
    trained with `affnerf train-segmenter` on your object families, --segmenter FILE; --segmenter none leaves it
    out; its mask redrawn by GrabCut from its probabilities when OpenCV is installed), else the salient-object model
    of the optional extra affnerf[segment]; with --box X0 Y0 X1 Y1, inside that rectangle only: for auto the
    segmenter's mask cut to it when it is sure, else GrabCut), cropped, centred and resized the way training saw
    objects, and encoded. Unless --fit-steps is 0, the encoder's codes are then fitted to the photo (test-time
    inversion: the photo's camera is searched, assuming a --fov degree lens, and the codes are moved so the model
    renders the photo; a few seconds on a CPU). Writes OUT/input.png, OUT/mask.png (the mask used: fix it and pass
    it back with --mask), OUT/fit.png (after a fit: the crop | the fitted model at the camera found | its
    affordance), OUT/turntable/*.png and OUT/turntable.gif (RGB | affordance overlay), OUT/affordance_model.ply
    (vertex colours and an integer vertex property `affordance`), OUT/affordance_model.glb and OUT/prediction.json.
    Without --run, the model shipped with affnerf is used.

    Warnings (one line each on stderr; the outputs are written): the object could not be separated with confidence
    (no uniform background, it fills the frame or runs along its border, the segmenter is unsure of its mask, or two
    methods disagree: give --mask FILE), recorded under `separation` in prediction.json; --segment auto without the
    salient model installed (it falls back to GrabCut); the model predicts no
    surface, so no mesh is written (`"mesh": null` and a `mesh_note` in prediction.json).

    Exit codes: 0 done, warnings included; 2 bad input (an image that is missing, unreadable, a folder, blank or of
    one colour, an empty or mismatched mask, a run that cannot predict from photos, a --segmenter file that is
    not one or --segment segmenter with none to use, --segment salient or grabcut without the optional extra
    installed, a --box that holds no pixel of the image or is narrower than 8 pixels inside it).
    """
    from affnerf.predict.outputs import write_prediction
    from affnerf.predict.predictor import Predictor
    from affnerf.predict.shipped import shipped_model

    run = config.run if config.run is not None else shipped_model()
    summary = write_prediction(
        Predictor.load(run, config.device, config.chunk, fast=config.fast, grid_threshold=config.grid_threshold),
        replace(config, run=run),
    )
    shown = {k: summary[k] for k in ("classes_present", "surface_area_m2")}
    if summary["fit"] is not None:  # the photo's camera in short (its pose matrix is in prediction.json)
        shown["camera"] = {k: v for k, v in summary["fit"]["camera"].items() if k != "c2w"}
    print(json.dumps(shown, indent=1))
    print(f"-> {config.out}")
