"""The protocol's 3D scoring on the tiny dataset with methods built here: one that gives each object's own true mesh
(an oracle: the 3D metrics must be near perfect, which checks frames and labels end to end) and one whose field
never reaches a surface (an empty mesh); and the 3D and stability tables of the report."""

from __future__ import annotations

import numpy as np
import pytest

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.data.raycast import FrameCaster
from affnerf.data.writer import surface_from_record
from affnerf.eval.protocol import Prediction, ProtocolConfig, TargetSet, evaluate, merge_metrics, merge_settings
from affnerf.eval.report import table2_markdown
from affnerf.eval.stability import StabilityRecord, merge_stability, stability_json
from affnerf.meshio import LabelledMesh, read_labelled_ply
from affnerf.metrics.surface import SURFACE_KEYS


class TrueMeshMethod:
    """Ray-casts each object's own ``mesh.ply`` at the targets and gives that mesh."""

    name = "oracle"

    def mesh(self, obj: ObjectData, inputs: list[int]) -> LabelledMesh:
        return read_labelled_ply(obj.folder / "mesh.ply")

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        caster = FrameCaster(surface_from_record(self.mesh(obj, inputs)), targets.background)
        frames = [caster.cast_frame(targets.intrinsics, pose) for pose in targets.poses]
        return Prediction(np.stack([f.affordance for f in frames]), np.stack([f.rgb / 255.0 for f in frames]))


class NoSurfaceMethod:
    """Background everywhere, and a mesh without faces (a field that never reaches its surface density)."""

    name = "no-surface"

    def mesh(self, obj: ObjectData, inputs: list[int]) -> LabelledMesh:
        return LabelledMesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64), face_props={"affordance": np.zeros(0)})

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        k = targets.intrinsics
        return Prediction(np.zeros((len(targets.poses), k.height, k.width), np.uint8))


@pytest.fixture(scope="module")
def objects(train_dataset) -> tuple[list[ObjectData], int]:
    ds = Dataset.open(train_dataset)
    return [ds.load_object(e) for e in ds.objects("test")], len(ds.affordance_classes)


PROTOCOL = ProtocolConfig(target_views=2, scale=0.25, metrics_3d=True)


def test_the_true_mesh_scores_near_perfectly(objects):
    result = evaluate(TrueMeshMethod(), objects[0], PROTOCOL, "test", objects[1]).to_json()
    for block in [*result["categories"].values(), result["mean"]]:
        assert block["chamfer_l1"] < 0.002 and block["fscore_1cm"] > 0.99
        # independent samples: points near a part boundary may take the neighbour's label (thin parts lose most)
        assert block["affordance_miou_3d"] > 0.9 and block["meshes_empty"] == 0
    for cat in result["categories"].values():  # per class: the oracle is right but for a few edge pixels
        conf = np.array(cat["confusion"])
        assert conf.sum() > 0 and np.trace(conf) / conf.sum() > 0.95
        present = [c for c in cat["IoU_per_class"] if c is not None]
        assert len(present) == (conf.sum(axis=1) > 0).sum()
        assert np.isclose(np.mean(present), cat["mIoU"])


def test_an_empty_mesh_scores_zero_without_a_chamfer_distance(objects):
    result = evaluate(NoSurfaceMethod(), objects[0], PROTOCOL, "test", objects[1]).to_json()
    for block in [*result["categories"].values(), result["mean"]]:
        assert block["fscore_1cm"] == 0.0 and block["affordance_miou_3d"] == 0.0
        assert block["chamfer_l1"] is None
    assert result["mean"]["meshes_empty"] == 2


def test_stability_of_the_oracle_is_zero_and_the_tables_mark_the_lowest_chamfer(objects):
    config = ProtocolConfig(target_views=2, scale=0.25, metrics_3d=True, stability_views=3)
    oracle = evaluate(TrueMeshMethod(), objects[0], config, "test", objects[1]).to_json()
    empty = evaluate(NoSurfaceMethod(), objects[0], config, "test", objects[1]).to_json()
    assert oracle["stability"]["mean"] == {"mIoU_spread": 0.0, "fscore_1cm_spread": 0.0, "objects": 2}
    assert empty["stability"]["mean"]["fscore_1cm_spread"] == 0.0
    table = table2_markdown([oracle, empty])
    chamfer = next(line for line in table.splitlines() if line.startswith("| chamfer_l1 | oracle |"))
    assert chamfer.count("**") == 2 * 3  # lowest in both categories and the average
    assert "| mIoU_spread | oracle | **0.000** |" in table
    two_d = evaluate(TrueMeshMethod(), objects[0], ProtocolConfig(target_views=2, scale=0.25), "test", objects[1])
    assert not set(SURFACE_KEYS) & set(two_d.to_json()["mean"]) and "stability" not in two_d.to_json()
    assert "3D (conventions" not in table2_markdown([two_d.to_json()])


def test_evaluations_of_disjoint_categories_merge_into_the_evaluation_of_all(objects):
    everything, num_classes = objects
    whole = evaluate(TrueMeshMethod(), everything, PROTOCOL, "test", num_classes).to_json()
    categories = sorted({o.record.category for o in everything})
    assert len(categories) == 2
    parts = [
        evaluate(TrueMeshMethod(), [o for o in everything if o.record.category == c], PROTOCOL, "test", num_classes)
        for c in categories
    ]
    merged = merge_metrics([p.to_json() for p in reversed(parts)])
    assert merged["categories"] == whole["categories"] and list(merged["categories"]) == categories
    assert merged["mean"] == pytest.approx(whole["mean"])
    with pytest.raises(ValueError, match="evaluated twice"):
        merge_metrics([parts[0].to_json(), parts[0].to_json()])
    other = {**parts[1].to_json(), "method": "retrieval"}
    with pytest.raises(ValueError, match="different methods"):
        merge_metrics([parts[0].to_json(), other])


def test_view_stability_of_disjoint_categories_merges_into_that_of_all(objects):
    everything, num_classes = objects
    config = ProtocolConfig(target_views=2, scale=0.25, metrics_3d=True, stability_views=3)
    whole = evaluate(TrueMeshMethod(), everything, config, "test", num_classes).to_json()
    categories = sorted({o.record.category for o in everything})
    parts = [
        evaluate(TrueMeshMethod(), [o for o in everything if o.record.category == c], config, "test", num_classes)
        for c in categories
    ]
    merged = merge_metrics([p.to_json() for p in parts])
    assert merged["stability"] == whole["stability"] and len(merged["stability"]["objects"]) == 2
    without = {k: v for k, v in parts[1].to_json().items() if k != "stability"}
    with pytest.raises(ValueError, match="only some parts"):
        merge_metrics([parts[0].to_json(), without])


def test_merged_stability_recomputes_spreads_and_means_from_the_records():
    a = stability_json([StabilityRecord("a_0", "a", [[0], [1]], [0.5, 0.7], [0.9, 0.6])], 2)
    b = stability_json([StabilityRecord("b_0", "b", [[0], [1]], [0.4, 0.4], [None, 0.5])], 2)
    merged = merge_stability([b, a])
    assert merged["mean"]["mIoU_spread"] == pytest.approx(0.1)  # (0.2 + 0.0) / 2 categories
    assert merged["mean"]["fscore_1cm_spread"] == pytest.approx(0.3)  # b has no spread: a missing F-score
    assert merged["mean"]["objects"] == 2 and set(merged["objects"]) == {"a_0", "b_0"}
    assert merged["categories"]["a"] == a["categories"]["a"]
    with pytest.raises(ValueError, match="more than one part"):
        merge_stability([a, a])
    with pytest.raises(ValueError, match="different numbers"):
        merge_stability([a, {**b, "views": 3}])


def test_merged_settings_name_every_part_and_the_longest_time():
    parts = [{"categories": "pen", "seconds": 4.0, "scale": "0.5"}, {"categories": "bottle", "seconds": 6.5}]
    merged = merge_settings(parts)
    assert merged == {"categories": "pen | bottle (2 processes side by side)", "seconds": 6.5, "scale": "0.5"}
    assert merge_settings([None, parts[0]]) is None and merge_settings([]) is None


def test_methods_given_one_and_three_input_views_are_pictured_at_one_camera(objects):
    objs, n = objects
    one = evaluate(TrueMeshMethod(), objs, ProtocolConfig(1, 3, 0.25), "test", n, keep_examples=2)
    three = evaluate(TrueMeshMethod(), objs, ProtocolConfig(3, 3, 0.25), "test", n, keep_examples=2)
    assert len(one.examples) == len(three.examples) == 2
    for a, b in zip(one.examples, three.examples, strict=True):
        assert a["object_id"] == b["object_id"]
        np.testing.assert_array_equal(a["input"], b["input"])
        np.testing.assert_array_equal(a["gt_labels"], b["gt_labels"])
        shown, truth = a["labels"] > 0, a["gt_labels"] > 0  # the prediction shown is at that camera too
        assert (shown & truth).sum() / (shown | truth).sum() > 0.7
        assert a["gt_labels"].any()  # the object is in view
