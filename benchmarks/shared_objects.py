"""The two real PartNet-Mobility objects of ``../shared/data`` (a bottle and a cabinet), each predicted from six
views: pictures to look at and a few scores. For checking only: the objects are never trained on, and nothing of
them but the pictures and the scores is written into the repository.

For each object it

1. imports it into a temporary dataset with the project's importer (``import_partnet``, the shipped part-name ->
   affordance table passed as the mapping, one importer view) to get its ground-truth ``mesh.ply`` in the
   canonical frame, and ray-casts six input photos of the textured object (``FrameCaster``) at 400x300 from
   azimuths 0, 60, ..., 300 degrees (0 = the object's front, -y) at 30 degrees elevation and 0.7 m, inside the
   training cameras' band (conventions section 1: elevation 10-80 degrees, distance 0.5-0.9 m);
2. predicts from each photo alone with the checkpoint through :class:`~affnerf.predict.predictor.Predictor`, as
   ``affnerf predict`` does (the photo separated with ``segment="auto"``, the labelled mesh at the object's own
   level: ``surface_density``, lowered per object by ``surface_optical_depth``; marching cubes at 128), renders one
   novel view from a fixed canonical camera (the same
   for all six inputs) and scores the mesh against the true mesh (F-score at 1 cm and 3D affordance mIoU, with
   :mod:`affnerf.eval.surface`) and the novel view's labels against the true affordance map there (2D mIoU,
   background counted as in conventions section 5, and its object-only variant);
3. writes ``results/shared_<id>.png`` (a ground-truth row, then one row per input: input | predicted affordance at
   the novel view | predicted mesh by affordance) and ``results/shared_objects.json`` (per view and per object:
   the scores, mean and spread = max - min over the six views; the checkpoint's path, step and sha256; the
   machine; the date).

    nice -n 19 env OMP_NUM_THREADS=1 .venv/bin/python benchmarks/shared_objects.py \\
        [--checkpoint src/affnerf/weights/affnerf-small.pt] [--data ../shared/data/partnet-mobility] \\
        [--work /tmp/affnerf-shared-objects] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import time
from importlib import resources
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.cameras import Intrinsics, look_at
from affnerf.data.importer import ImportConfig, _object_rng, import_partnet
from affnerf.data.partnet import load_partnet_object
from affnerf.data.raycast import FrameCaster
from affnerf.environment import describe_machine
from affnerf.eval.surface import mesh_samples, sample_seed, score_mesh
from affnerf.meshio import LabelledMesh, read_labelled_ply
from affnerf.metrics.segmentation import confusion_matrix, mean_iou, object_only
from affnerf.objects.asset import merge_parts
from affnerf.pictures.compose import fit_height, legend, overlay_affordance, stack_rows, text_strip
from affnerf.pictures.meshes import affordance_colors, coloured_surface, views_around
from affnerf.predict.invert import InversionConfig
from affnerf.predict.outputs import PredictConfig
from affnerf.predict.predictor import Predictor
from affnerf.predict.shipped import shipped_model

OBJECTS = ("3763", "40147")
#: Input views: azimuths from the object's front (-y), degrees, at one elevation and distance in the training band.
INPUT_AZIMUTHS = (0, 60, 120, 180, 240, 300)
INPUT_ELEVATION, INPUT_RADIUS = 30.0, 0.7
#: The fixed novel view, the same for every input: front-right, a little higher than the inputs.
NOVEL_AZIMUTH, NOVEL_ELEVATION, NOVEL_RADIUS = 30.0, 40.0, 0.75
WIDTH, HEIGHT, FOV_X = 400, 300, math.radians(60.0)
NOVEL_WIDTH, NOVEL_HEIGHT = 200, 150
MESH_RESOLUTION = 128
#: Mesh pictures: two sides, yaw about +z in the picture helper's convention (0 = from +x).
MESH_YAWS = (-60.0, 30.0)
#: Distance of the mesh pictures' cameras from the origin: the whole canonical cube in view.
MESH_REACH = 0.85
TILE = 200
SEED = 0


def camera(azimuth_deg: float, elevation_deg: float, radius: float) -> np.ndarray:
    """Camera-to-world (4, 4) looking at the origin; azimuth 0 looks from -y (the front), growing anticlockwise."""
    yaw = math.radians(azimuth_deg - 90.0)
    elev = math.radians(elevation_deg)
    eye = radius * np.array([math.cos(elev) * math.cos(yaw), math.cos(elev) * math.sin(yaw), math.sin(elev)])
    return look_at(eye, np.zeros(3))


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def shipped_mapping() -> Path:
    """The part-name -> affordance table shipped with affnerf (README, 'Real objects: PartNet-Mobility')."""
    return Path(str(resources.files("affnerf.data.partnet").joinpath("mapping.yaml")))


def import_objects(data: Path, work: Path) -> dict[str, dict]:
    """Import the objects into ``work/dataset`` and return, per object, its id, folder, category and the textured
    surface to ray-cast (checked to be the importer's own ``mesh.ply`` geometry)."""
    sources = [data / name for name in OBJECTS]
    config = ImportConfig(out=work / "dataset", views=1, split="test", mapping=shipped_mapping(), overwrite=True)
    entries = import_partnet(sources, config, progress=False)
    out = {}
    for src, entry in zip(sources, entries, strict=True):
        asset = load_partnet_object(src, config.joint_state, _object_rng(config.seed, src.name), config.mapping)
        surface = merge_parts(asset)
        folder = config.out / entry.path
        truth = read_labelled_ply(folder / "mesh.ply")
        if truth.vertices.shape != surface.vertices.shape or not np.allclose(
            truth.vertices, surface.vertices, atol=1e-5
        ):
            raise SystemExit(f"{folder / 'mesh.ply'}: the textured surface does not match the imported mesh")
        out[src.name] = {"id": entry.id, "category": entry.category, "folder": folder, "surface": surface,
                         "truth": truth}  # fmt: skip
    return out


def miou_2d(truth: np.ndarray, pred: np.ndarray, classes: int) -> tuple[float, float]:
    """2D mIoU (background counted, as in conventions section 5) and its object-only variant."""
    conf = confusion_matrix(truth, pred, classes)
    return mean_iou(conf), mean_iou(object_only(conf))


def predict_view(
    predictor: Predictor, image: Path, novel: np.ndarray, fit_steps: int
) -> tuple[np.ndarray, np.ndarray, LabelledMesh, str]:
    """From one photo: the novel view's RGB (uint8) and labels, the labelled mesh, and how the object was separated
    (with ``fit_steps`` of test-time inversion first, as ``affnerf predict``; 0 = the encoder's codes)."""
    obj = predictor.encode_image(image, segment="auto")
    if fit_steps > 0:
        predictor.fit(obj, InversionConfig(steps=fit_steps), FOV_X)
    intr = Intrinsics.from_fov(NOVEL_WIDTH, NOVEL_HEIGHT, FOV_X)
    view = predictor.render(obj, intr, novel)
    mesh = predictor.mesh(obj, MESH_RESOLUTION)
    rgb = np.round(np.clip(view.rgb, 0, 1) * 255).astype(np.uint8)
    return rgb, view.labels, mesh, obj.prepared.source


def tile(image: np.ndarray) -> np.ndarray:
    return fit_height(image, TILE)


def mesh_tile(mesh: LabelledMesh) -> np.ndarray:
    """The mesh by affordance from two sides, framed on the canonical cube (not on the mesh, as
    :func:`~affnerf.pictures.meshes.mesh_preview` does), so every mesh is shown at its true size and place."""
    if not len(mesh.faces):
        return np.full((TILE, TILE * len(MESH_YAWS), 3), 255, np.uint8)
    surface = coloured_surface(mesh.vertices, mesh.faces, affordance_colors(mesh.face_props["affordance"]))
    return views_around(surface, np.zeros(3), MESH_REACH, MESH_YAWS, TILE)


def picture_row(label: str, tiles: list[np.ndarray]) -> np.ndarray:
    body = np.concatenate([np.pad(t, ((0, 0), (0, 4), (0, 0)), constant_values=255) for t in tiles], axis=1)
    return stack_rows([text_strip(label, body.shape[1], 16), body, np.full((4, body.shape[1], 3), 255, np.uint8)])


def fmt(value: float | None) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value:.3f}"


def spread(values: list[float | None]) -> dict[str, float | None]:
    finite = [v for v in values if v is not None and math.isfinite(v)]
    if not finite:
        return {"mean": None, "min": None, "max": None, "spread": None}
    return {"mean": float(np.mean(finite)), "min": min(finite), "max": max(finite),
            "spread": max(finite) - min(finite)}  # fmt: skip


def predict_and_score(
    predictor: Predictor, rgb: np.ndarray, az: int, info: dict, image: Path, truth: tuple, fit_steps: int
) -> tuple[dict, np.ndarray, set[int]]:
    """Predict from one ray-cast input photo (saved to ``image``) and score it against ``truth`` (the novel pose,
    its true affordance and the true mesh's samples): the view's record, its picture row and the classes it shows."""
    novel_pose, true_affordance, truth_samples = truth
    started = time.perf_counter()
    image.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(rgb).save(image)
    pred_rgb, labels, mesh, separated_by = predict_view(predictor, image, novel_pose, fit_steps)
    score = score_mesh(mesh, truth_samples, sample_seed(SEED, info["id"]))
    m2d, m2d_obj = miou_2d(true_affordance, labels, len(predictor.classes))
    seen = set(np.unique(labels).tolist()) | set(np.unique(mesh.face_props["affordance"]).tolist())
    record = {
        "azimuth_deg": az,
        "fscore_1cm": score["fscore_1cm"],
        "affordance_miou_3d": score["affordance_miou_3d"],
        "chamfer_l1": score["chamfer_l1"],
        "miou_2d": m2d,
        "miou_2d_object": m2d_obj,
        "mesh_faces": len(mesh.faces),
        "separated_by": separated_by,
        "seconds": round(time.perf_counter() - started, 1),
    }
    shown = {k: v for k, v in record.items() if k not in ("azimuth_deg", "separated_by")}
    print(f"{info['id']} az {az:3d}: " + ", ".join(f"{k} {v}" for k, v in shown.items()), flush=True)
    row = picture_row(
        f"input az {az} deg -> F@1cm {fmt(record['fscore_1cm'])}, 3D mIoU "
        f"{fmt(record['affordance_miou_3d'])}, 2D mIoU {fmt(m2d)}, {len(mesh.faces)} faces",
        [tile(rgb), tile(overlay_affordance(pred_rgb, labels)), mesh_tile(mesh)],
    )
    return record, row, seen


def write_sheet(rows: list[np.ndarray], present: set[int], classes, path: Path) -> None:
    """The object's picture: a header, its rows and the legend of the classes present, as a palette PNG."""
    width = max(r.shape[1] for r in rows)
    header = text_strip(
        "columns: input (ray-cast photo) | predicted affordance at a fixed novel view (az 30, el 40) | "
        "predicted mesh by affordance (front-right, back-right)",
        width,
        16,
    )
    ids = sorted(c for c in present if c > 0)
    sheet = stack_rows([header, *rows, legend(ids, classes, width)])
    Image.fromarray(sheet).quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)


def run_object(
    name: str,
    info: dict,
    predictor: Predictor,
    work: Path,
    out: Path,
    azimuths: tuple[int, ...] = INPUT_AZIMUTHS,
    fit_steps: int = PredictConfig.fit_steps,
) -> dict:
    classes = predictor.classes
    caster = FrameCaster(info["surface"])
    input_intr = Intrinsics.from_fov(WIDTH, HEIGHT, FOV_X)
    novel_pose = camera(NOVEL_AZIMUTH, NOVEL_ELEVATION, NOVEL_RADIUS)
    true_novel = caster.cast_frame(Intrinsics.from_fov(NOVEL_WIDTH, NOVEL_HEIGHT, FOV_X), novel_pose)
    truth_samples = mesh_samples(info["truth"], sample_seed(SEED, info["id"]) + [1])
    present = set(np.unique(info["truth"].face_props["affordance"]).tolist())
    rows = [
        picture_row(
            f"ground truth ({info['id']}, PartNet-Mobility {name}): novel view | its affordance | mesh "
            f"({len(info['truth'].faces)} faces)",
            [tile(true_novel.rgb), tile(overlay_affordance(true_novel.rgb, true_novel.affordance)),
             mesh_tile(info["truth"])],
        )
    ]  # fmt: skip
    views = []
    for az in azimuths:
        frame = caster.cast_frame(input_intr, camera(az, INPUT_ELEVATION, INPUT_RADIUS))
        image = work / "inputs" / f"{name}_az{az:03d}.png"
        truth = (novel_pose, true_novel.affordance, truth_samples)
        record, row, seen = predict_and_score(predictor, frame.rgb, az, info, image, truth, fit_steps)
        views.append(record)
        rows.append(row)
        present |= seen
    path = out / f"shared_{name}.png"
    write_sheet(rows, present, classes, path)
    summary = {key: spread([v[key] for v in views])
               for key in ("fscore_1cm", "affordance_miou_3d", "miou_2d", "miou_2d_object", "mesh_faces")}  # fmt: skip
    return {
        "object_id": info["id"],
        "category": info["category"],
        "partnet_id": name,
        "true_mesh_faces": len(info["truth"].faces),
        "picture": path.name,
        "views": views,
        "summary": summary,
    }


def parse_args() -> argparse.Namespace:
    """The command line."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--checkpoint", type=Path, default=shipped_model())
    parser.add_argument(
        "--data", type=Path, default=Path(__file__).resolve().parents[2] / "shared/data/partnet-mobility"
    )
    parser.add_argument("--work", type=Path, default=Path("/tmp/affnerf-shared-objects"))
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results")
    parser.add_argument("--objects", nargs="*", default=list(OBJECTS))
    parser.add_argument("--azimuths", nargs="*", type=int, default=list(INPUT_AZIMUTHS), help="for quick checks")
    parser.add_argument("--fit-steps", type=int, default=PredictConfig.fit_steps, help="0: the encoder's codes")
    return parser.parse_args()


def main() -> None:
    args = parse_args()
    started = time.perf_counter()
    args.work.mkdir(parents=True, exist_ok=True)
    args.out.mkdir(parents=True, exist_ok=True)
    predictor = Predictor.load(args.checkpoint, "cpu")
    infos = import_objects(args.data, args.work)
    from affnerf.vocab import AFFORDANCE_CLASSES

    if list(predictor.classes) != list(AFFORDANCE_CLASSES):
        raise SystemExit(f"{args.checkpoint}: its classes differ from the dataset's")
    objects = {
        name: run_object(name, infos[name], predictor, args.work, args.out, tuple(args.azimuths), args.fit_steps)
        for name in args.objects
    }
    checkpoint = Path(predictor.loaded.path).resolve()
    try:
        shown = str(checkpoint.relative_to(Path(__file__).resolve().parents[1]))
    except ValueError:
        shown = str(checkpoint)
    result = {
        "benchmark": "shared_objects",
        "checkpoint": {"path": shown, "step": predictor.loaded.step, "sha256": sha256(checkpoint)},
        "settings": {
            "input_azimuths_deg": list(args.azimuths),
            "fit_steps": args.fit_steps,
            "input_elevation_deg": INPUT_ELEVATION,
            "input_radius_m": INPUT_RADIUS,
            "input_size": [WIDTH, HEIGHT],
            "novel_view": {
                "azimuth_deg": NOVEL_AZIMUTH,
                "elevation_deg": NOVEL_ELEVATION,
                "radius_m": NOVEL_RADIUS,
                "size": [NOVEL_WIDTH, NOVEL_HEIGHT],
            },
            "mesh_resolution": MESH_RESOLUTION,
            "surface_density": predictor.surface_level(),
            "segment": "auto",
            "seed": SEED,
            "note": "azimuth 0 = the object's front (-y); miou_2d counts background (conventions section 5)",
        },  # fmt: skip
        "objects": objects,
        "machine": describe_machine(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        "seconds": round(time.perf_counter() - started, 1),
    }
    path = args.out / "shared_objects.json"
    path.write_text(json.dumps(result, indent=1) + "\n")
    for name, obj in objects.items():
        s = obj["summary"]
        print(f"{name} ({obj['object_id']}): " + ", ".join(
            f"{k} {fmt(v['mean'])} (spread {fmt(v['spread'])})" for k, v in s.items()))  # fmt: skip
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
