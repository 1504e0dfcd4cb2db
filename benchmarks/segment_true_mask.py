"""How much of the loss from a cluttered photo is the mask (issue 16): predictions from the composites of
``bench_segment.py`` (the same seeded draws) given their *true* mask, from the object at the same size and place on a
white background, and from the clean render, each scored like ``bench_segment.py --checkpoint`` does (the shipped
model fitted to the photo for 30 steps; affordance mIoU at the object's other views, F@1cm of the mesh).

Run::

    .venv/bin/python benchmarks/segment_true_mask.py --data /tmp/seg/data \
        --out benchmarks/results/segment_true_mask.json
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.eval.surface import true_samples
from affnerf.predict.predictor import Predictor
from affnerf.predict.shipped import shipped_model

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import backgrounds, bench_composites, composite, replay_args  # noqa: E402
from bench_segment import score_photo  # noqa: E402

KINDS = ("composite, true mask", "white background, same size", "clean render")


def main() -> None:
    args = replay_args(__doc__)
    tmp, bgs = Path(tempfile.mkdtemp()), backgrounds()
    predictor = Predictor.load(Path(shipped_model()), "auto")
    rows = []
    for c in bench_composites(args.data, 0, args.composites):
        obj, view = c.obj, c.view
        white_photo = np.full_like(bgs[c.background], 255)  # the same size and place, on white
        white, _ = composite(obj.rgb(view), obj.affordance(view) > 0, white_photo, False, c.draws)
        for name, image in (("c.png", c.rgb), ("m.png", c.truth.astype(np.uint8) * 255), ("w.png", white)):
            Image.fromarray(image).save(tmp / name)
        Image.fromarray(obj.rgb(view)).save(tmp / "r.png")
        others, truth_3d = [i for i in range(len(obj.record.frames)) if i != view], true_samples(obj, 0)
        row = {"object": obj.record.object_id, "background": c.background}
        for kind, photo, mask in zip(KINDS, ("c.png", "w.png", "r.png"), (tmp / "m.png", None, None), strict=True):
            scores = score_photo(predictor, obj, tmp / photo, others, 30, truth_3d, mask=mask)
            row[kind] = {m: round(float(v), 4) for m, v in scores.items()}
        rows.append(row)
        print(c.index, row, flush=True)
    summary = {n: {m: round(float(np.mean([r[n][m] for r in rows])), 4) for m in ("miou", "fscore_1cm")} for n in KINDS}
    print(json.dumps(summary))
    args.out.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
