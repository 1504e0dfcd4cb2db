"""``affnerf data ...``: generate, import, index, preview and summarise datasets."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import tyro
from tyro.conf import Positional
from tyro.extras import SubcommandApp

from affnerf.data.generate import GenerateConfig
from affnerf.data.importer import ImportConfig

app = SubcommandApp()


@app.command(name="generate")
def generate(config: Annotated[GenerateConfig, tyro.conf.arg(name="")]) -> None:
    """Generate (or resume) a procedural, part-annotated multi-view dataset.

    Writes dataset.json and one folder per object (rgb/, depth/, affordance/, part/, transforms.json, mesh.ply).
    A rerun skips finished objects; --shard I/N lets N processes fill one folder.
    """
    from affnerf.data.generate import generate_dataset

    report = generate_dataset(config)
    print(
        f"{len(report.made)} objects made, {len(report.skipped)} already complete; "
        f"{report.frames} frames in {report.seconds:.1f} s ({report.frames_per_second:.1f} frames/s) -> {config.out}"
    )


@app.command(name="import-partnet")
def import_partnet(src: Positional[list[Path]], config: Annotated[ImportConfig, tyro.conf.arg(name="")]) -> None:
    """Add PartNet-Mobility objects (folders with mobility.urdf, result.json, textured_objs/, meta.json) to a dataset.

    Leaf part names map to affordances through the shipped table (docs/conventions.md §3); --mapping FILE overrides
    or extends it. A model_cat the table lacks needs a mapping file; a minimal one (YAML):

        Mug:                # meta.json's model_cat
          category: mug     # the affnerf category to file it under
          default: contain  # the affordance of parts not named below
          parts:            # optional: result.json part name -> affordance
            handle: grasp

    Affordances: grasp, cut, screw, write, open, pull, pour, contain, wear, view, support.

    An object already in the dataset is kept when imported again with the same settings; with other settings
    (views, size, joint state, split, seed, mapping) the import is refused unless --overwrite replaces it.

    Exit codes: 0 done; 2 bad input (a malformed object, a model_cat without mapping, an object already imported
    with other settings and no --overwrite; nothing is written).
    """
    from affnerf.data.importer import import_partnet as run

    entries = run(src, config)
    for e in entries:
        print(f"imported {e.id} ({e.category}, {e.split}) -> {Path(config.out) / e.path}")


@app.command(name="index")
def index(root: Positional[Path]) -> None:
    """Rebuild DIR/dataset.json from the complete object folders under DIR."""
    from affnerf.data.index import rebuild_index

    idx = rebuild_index(root)
    print(f"{root / 'dataset.json'}: {len(idx.objects)} objects")


@app.command(name="preview")
def preview(root: Positional[Path], out: Path, objects: int = 8, views: int = 3, split: str | None = None) -> None:
    """Write a contact sheet (RGB | depth | affordance overlay, with a legend) over several objects and views.

    Args:
        root: dataset folder.
        out: PNG to write.
        objects: number of objects (taken round-robin over categories).
        views: views per object.
        split: only objects of this split.
    """
    from affnerf.pictures.sheets import write_preview

    print(write_preview(root, out, objects=objects, views=views, split=split))


@app.command(name="stats")
def stats(root: Positional[Path], views_per_object: int = 8, json_out: Path | None = None) -> None:
    """Print objects per category and split, and the pixel share of each affordance.

    Args:
        root: dataset folder.
        views_per_object: frames read per object for the pixel shares (0 = all).
        json_out: also write the statistics as JSON here.
    """
    from affnerf.data.stats import dataset_stats
    from affnerf.fileio import write_json_atomic

    result = dataset_stats(root, views_per_object)
    print(result.table())
    if json_out is not None:
        write_json_atomic(json_out, result.to_json())
        print(f"-> {json_out}")


__all__ = ["app"]
