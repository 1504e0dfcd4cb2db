"""From one image to a 3D affordance model: encode, render a turntable, extract and export the labelled mesh.

Python use::

    from affnerf.predict.predictor import Predictor
    p = Predictor.load("runs/mini")                      # a run folder or a checkpoint
    obj = p.encode_image("mug.png")                      # codes of the object in the photo (segment="auto")
    p.fit(obj, InversionConfig())                        # optional: fit the codes to the photo (a few seconds)
    view = p.render(obj, intrinsics, c2w)                # RGB, depth, affordance at any camera
    mesh = p.mesh(obj, resolution=128)                   # LabelledMesh with per-vertex affordance
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, Intrinsics, look_at
from affnerf.errors import input_error
from affnerf.meshio import LabelledMesh
from affnerf.model.affnerf import Codes
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.model.views import RenderedView, render_view
from affnerf.predict.agreement import confirmed
from affnerf.predict.image import PreparedImage, prepare_image
from affnerf.predict.invert import InversionConfig, InversionResult, crop_target, invert
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.mesh import model_surface
from affnerf.predict.segment import Box, SegmentMethod
from affnerf.rendering.grid import OccupancyGrid


@dataclass
class EncodedObject:
    """An object seen in one image: its codes, how its image was prepared, (once built) its occupancy grid, and
    (once fitted to its image) how the fit went, the intrinsics of the crop it was fitted in (with
    ``inversion.camera``, the camera of the encoders' crop in the canonical frame) and the encoders' codes before
    the fit."""

    codes: Codes
    prepared: PreparedImage | None = None
    grid: OccupancyGrid | None = None
    inversion: InversionResult | None = None
    crop_camera: Intrinsics | None = None
    encoder_codes: Codes | None = None


def turntable_poses(count: int, elevation_deg: float = 25.0, radius: float = 0.75) -> np.ndarray:
    """(count, 4, 4) cameras circling the canonical frame's z axis, looking at the origin.

    Example:
        >>> turntable_poses(4).shape
        (4, 4, 4)
    """
    elev = math.radians(elevation_deg)
    poses = []
    for k in range(count):
        yaw = 2.0 * math.pi * k / count - math.pi / 2.0  # the first view looks from -y, the objects' front
        eye = radius * np.array([math.cos(elev) * math.cos(yaw), math.cos(elev) * math.sin(yaw), math.sin(elev)])
        poses.append(look_at(eye, np.zeros(3)))
    return np.stack(poses)


def pick_device(name: str) -> torch.device:
    """``auto`` -> CUDA when available, else CPU."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


class Predictor:
    """A trained model with the operations of prediction.

    Args:
        loaded: the model.
        chunk: rays per forward pass.
        fast: render and extract meshes with the object's occupancy grid (empty-space skipping); False renders
            coarse-to-fine as in training and evaluates the density everywhere.
        grid_resolution: cells per side of the occupancy grid.
        grid_threshold: density above which a cell is occupied (None: the model config's ``occupancy_density``).
        grid_samples: samples per ray inside occupied cells.
    """

    def __init__(
        self,
        loaded: LoadedModel,
        chunk: int = RAYS_PER_CHUNK,
        fast: bool = True,
        grid_resolution: int = 64,
        grid_threshold: float | None = None,
        grid_samples: int = 32,
    ) -> None:
        self.loaded = loaded
        self.chunk = chunk
        self.fast = fast
        self.grid_resolution, self.grid_threshold, self.grid_samples = grid_resolution, grid_threshold, grid_samples

    @classmethod
    def load(cls, path: Path, device: str = "auto", chunk: int = RAYS_PER_CHUNK, **options: object) -> Predictor:
        """Load from a run folder or checkpoint file (an AFF-NeRF or pose-aware model: prediction from a photo needs
        no pose)."""
        loaded = load_model(Path(path), pick_device(device))
        if loaded.model.needs_input_pose:
            raise input_error(
                loaded.path,
                f"a {loaded.model.config.kind} model needs the input camera's pose; "
                "predict from photos with an AFF-NeRF (or pose-aware) run",
            )
        return cls(loaded, chunk, **options)  # type: ignore[arg-type]

    def grid(self, obj: EncodedObject) -> OccupancyGrid:
        """The object's occupancy grid, built on first use."""
        if obj.grid is None:
            obj.grid = self.loaded.model.occupancy(obj.codes, self.grid_resolution, self.grid_threshold)
        return obj.grid

    @property
    def classes(self) -> list[str]:
        return self.loaded.classes

    @torch.no_grad()
    def encode_crops(self, crops: np.ndarray) -> Codes:
        """Codes of (B, S, S, 3) uint8 encoder crops."""
        images = torch.from_numpy(np.ascontiguousarray(crops)).permute(0, 3, 1, 2).float() / 255.0
        return self.loaded.model.encode(images.to(self.loaded.device))

    def encode_image(
        self,
        image: Path,
        mask: Path | None = None,
        segment: SegmentMethod = "auto",
        segmenter: Path | None = None,
        box: Box | None = None,
    ) -> EncodedObject:
        """Prepare a photo (separate the object by ``mask`` or the ``segment`` method, which may use the object
        segmenter file ``segmenter``: ``None`` for the shipped one, ``segment.NO_SEGMENTER`` for none; inside the
        (x0, y0, x1, y1) rectangle ``box`` when given; crop, centre, resize) and encode it."""
        config = self.loaded.model.config
        prepared = prepare_image(
            Path(image), config.encoder_resolution, self.loaded.background, mask, segment, segmenter, box,
            config.crop_outside,
        )  # fmt: skip
        return EncodedObject(self.encode_crops(prepared.crop[None]), prepared)

    def fit(
        self, obj: EncodedObject, config: InversionConfig, camera_angle_x: float = DEFAULT_CAMERA_ANGLE_X
    ) -> InversionResult:
        """Fit the object's codes to its photo (test-time inversion, :mod:`affnerf.predict.invert`): the photo's
        camera is searched and the codes are moved to render the photo's crop. Replaces ``obj.codes`` and its
        grid; the result is also kept in ``obj.inversion``.

        Args:
            obj: an object encoded by :meth:`encode_image`.
            config: the fit's settings.
            camera_angle_x: the photo's horizontal field of view, radians.
        """
        if obj.prepared is None:
            raise ValueError("fit needs an object encoded from a photo (encode_image)")
        mask = obj.prepared.mask
        intr = Intrinsics.from_fov(mask.shape[1], mask.shape[0], camera_angle_x)
        k = np.array([intr.fl_x, intr.fl_y, intr.cx, intr.cy])
        size = self.loaded.model.config.encoder_resolution
        target = crop_target(obj.prepared.rgb, mask, k, size, self.loaded.background)
        result = invert(self.loaded.model, obj.codes, target, np.asarray(self.loaded.background), config)
        if obj.encoder_codes is None:
            obj.encoder_codes = obj.codes
        obj.codes, obj.grid, obj.inversion = result.codes, None, result
        obj.crop_camera = Intrinsics(size, size, *(float(v) for v in target.intrinsics))
        return result

    def render(self, obj: EncodedObject, intrinsics: Intrinsics, c2w: np.ndarray) -> RenderedView:
        """Render the object from a camera in its canonical frame."""
        grid = self.grid(obj) if self.fast else None
        return render_view(
            self.loaded.model, obj.codes, intrinsics, c2w, self.loaded.background, self.chunk, grid, self.grid_samples
        )

    def surface_level(self, level: float | None = None) -> float:
        """The model's base density of extracted surfaces: ``level`` when given, else the model config's
        ``surface_density`` (an object's own level may lie below it: :meth:`surface`)."""
        return self.loaded.model.config.surface_density if level is None else float(level)

    def surface(
        self, obj: EncodedObject, resolution: int = 128, level: float | None = None
    ) -> tuple[LabelledMesh, float]:
        """The labelled mesh of the object (marching cubes in the model's scene cube) and the density it was cut
        at: ``level`` when given, else the object's own level (:func:`affnerf.predict.level.object_level`)."""
        grid = self.grid(obj) if self.fast else None
        return model_surface(self.loaded.model, obj.codes, resolution, level, grid)

    def confirm(
        self, obj: EncodedObject, mesh: LabelledMesh, resolution: int = 128, level: float | None = None
    ) -> LabelledMesh:
        """``mesh`` of a fitted object with the face property ``confirmed``: where the encoders' codes before the
        fit put the same label within :data:`~affnerf.predict.agreement.AGREEMENT_DISTANCE`
        (:func:`affnerf.predict.agreement.confirmed`). An object never fitted gets ``mesh`` back unchanged."""
        if obj.encoder_codes is None:
            return mesh
        return confirmed(mesh, self.surface(EncodedObject(obj.encoder_codes), resolution, level)[0])

    def mesh(self, obj: EncodedObject, resolution: int = 128, level: float | None = None) -> LabelledMesh:
        """The labelled mesh of :meth:`surface`."""
        return self.surface(obj, resolution, level)[0]
