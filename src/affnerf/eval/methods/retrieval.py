"""Retrieval: the training object whose shape code is nearest renders its ground-truth affordance (and gives its
true labelled mesh for the 3D metrics).

A learned method that does not beat this has learned nothing beyond recognising the nearest training shape.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.data.format import IndexEntry
from affnerf.data.raycast import FrameCaster
from affnerf.data.writer import surface_from_record
from affnerf.errors import input_error
from affnerf.eval.protocol import Prediction, TargetSet
from affnerf.eval.registry import MethodContext, MethodSpec, register_method
from affnerf.meshio import LabelledMesh, read_labelled_ply
from affnerf.model.inputs import dataset_views
from affnerf.predict.loading import LoadedModel


def category_names(categories: list[str] | str | None) -> list[str] | None:
    """Category names from a list or comma-separated text; ``None`` (every category) for none.

    Example:
        >>> category_names("pen, bottle"), category_names(""), category_names(["cabinet"])
        (['pen', 'bottle'], None, ['cabinet'])
    """
    if isinstance(categories, str):
        categories = [c.strip() for c in categories.split(",") if c.strip()]
    return list(categories) if categories else None


def bank_entries(dataset: Dataset, categories: list[str] | str | None) -> list[IndexEntry]:
    """The objects of the retrieval bank: the dataset's train split, restricted to ``categories`` when given.

    Raises:
        AffnerfError: naming ``dataset.json``, when there are none (a dataset of test objects only, or one without
            the run's training categories).
    """
    names = category_names(categories)
    entries = [e for e in dataset.objects(split="train") if names is None or e.category in names]
    if not entries:
        which = "every category" if names is None else ", ".join(names)
        raise input_error(
            Path(dataset.root) / "dataset.json",
            f"the retrieval bank is empty: it holds the train-split objects of the run's training categories "
            f"({which}) and this dataset has none; evaluate retrieval on a dataset with such objects, e.g. the "
            f"one the run was trained on",
        )
    return entries


class RetrievalMethod:
    """Nearest training object by shape code (L2; AFF-NeRF or pose-aware), rendered from the target cameras.

    Args:
        loaded: a trained pose-free model, AFF-NeRF or pose-aware (its shape code embeds the images).
        dataset: the dataset holding the training objects and their ``mesh.ply``.
        categories: restrict the bank to these categories (a list or comma-separated text; None = every training
            object).
        views_per_object: views of each training object whose codes are averaged into its bank entry.
    """

    name = "retrieval"

    def __init__(
        self,
        loaded: LoadedModel,
        dataset: Dataset,
        categories: list[str] | str | None = None,
        views_per_object: int = 4,
    ) -> None:
        if loaded.model.needs_input_pose:
            raise ValueError("retrieval embeds images with the shape code of a pose-free model (AFF-NeRF, pose-aware)")
        self.loaded, self.dataset = loaded, dataset
        self.views_per_object = views_per_object
        self.entries: list[IndexEntry] = bank_entries(dataset, categories)
        self.bank = np.stack([self._embed(dataset.load_object(e), None) for e in self.entries])
        self._casters: dict[str, FrameCaster] = {}
        self._meshes: dict[str, LabelledMesh] = {}
        self._nearest: tuple[tuple[str, tuple[int, ...]], IndexEntry] | None = None

    @torch.no_grad()
    def _embed(self, obj: ObjectData, views: list[int] | None) -> np.ndarray:
        if views is None:
            views = np.linspace(0, len(obj) - 1, self.views_per_object).round().astype(int).tolist()
        model = self.loaded.model
        images, intr, poses = dataset_views(obj, views, model.config)
        codes = model.encode_views(
            images.to(self.loaded.device), intr.to(self.loaded.device), poses.to(self.loaded.device)
        )
        return codes.shape[0].cpu().numpy()

    def nearest(self, obj: ObjectData, inputs: list[int]) -> IndexEntry:
        """The training object nearest to the input views' shape code (kept for the last object and inputs)."""
        key = (obj.record.object_id, tuple(inputs))
        if self._nearest is None or self._nearest[0] != key:
            code = self._embed(obj, inputs)
            self._nearest = (key, self.entries[int(np.argmin(((self.bank - code) ** 2).sum(axis=1)))])
        return self._nearest[1]

    def true_mesh(self, entry: IndexEntry) -> LabelledMesh:
        """A bank object's ground-truth ``mesh.ply``."""
        if entry.id not in self._meshes:
            self._meshes[entry.id] = read_labelled_ply(self.dataset.root / entry.path / "mesh.ply")
        return self._meshes[entry.id]

    def mesh(self, obj: ObjectData, inputs: list[int]) -> LabelledMesh:
        """The retrieved training object's true mesh (face property ``affordance``)."""
        return self.true_mesh(self.nearest(obj, inputs))

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        entry = self.nearest(obj, inputs)
        if entry.id not in self._casters:
            mesh = self.true_mesh(entry)
            self._casters[entry.id] = FrameCaster(surface_from_record(mesh), targets.background)
        caster = self._casters[entry.id]
        frames = [caster.cast_frame(targets.intrinsics, pose) for pose in targets.poses]
        return Prediction(np.stack([f.affordance for f in frames]), np.stack([f.rgb / 255.0 for f in frames]))


def _build(context: MethodContext) -> RetrievalMethod:
    """The bank holds only what the run trained on: no peeking at a held-out category."""
    from affnerf.eval.methods.affnerf import load_run

    loaded = load_run(context, "affnerf", "retrieval")
    return RetrievalMethod(loaded, context.dataset, loaded.train_config.get("categories") or None)


register_method(MethodSpec("retrieval", _build, "the nearest training object by AFF-NeRF shape code, its true labels"))
