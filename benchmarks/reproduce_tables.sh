#!/usr/bin/env bash
# Reproduce the committed Table 2 / Table 3 results and the shipped model, on this machine (CPU: several hours).
# Every step is resumable: rerun the script after an interruption. Results land in benchmarks/results/.
set -euo pipefail
cd "$(dirname "$0")/.."
A=".venv/bin/affnerf"
W="${WORK:-benchmarks/.work/tables}"
R="benchmarks/results"
STEPS="${STEPS:-40000}"            # AFF-NeRF, small configuration, all eight categories
PIX_STEPS="${PIX_STEPS:-20000}"    # PixelNeRF-M baseline (3 input views)
LOCO_STEPS="${LOCO_STEPS:-15000}"  # leave-one-category-out runs
DEVICE="${DEVICE:-auto}"
resume() { [ -d "$1/checkpoints" ] && echo --resume || true; }

# 1. data: 8 categories x 20 objects (16 train, 2 val, 2 test each), 40 views of 400x300
$A data generate --out "$W/data" --objects-per-category 20 --views 40 --workers 2 --seed 0

# 2. training
$A train --data "$W/data" --out "$W/affnerf" --config small --steps "$STEPS" --device "$DEVICE" $(resume "$W/affnerf")
$A train --data "$W/data" --out "$W/pixelnerf" --config small --steps "$PIX_STEPS" --device "$DEVICE" \
    --model.kind pixelnerf --input-views 3 $(resume "$W/pixelnerf")
for held in teapot scissors; do
    cats=$(python3 -c "import sys; c='screwdriver pen scissors eyeglasses bucket bottle cabinet teapot'.split(); c.remove(sys.argv[1]); print(','.join(c))" "$held")
    $A train --data "$W/data" --out "$W/loco-$held" --config small --steps "$LOCO_STEPS" --device "$DEVICE" \
        --categories "$cats" $(resume "$W/loco-$held")
done

# 3. Table 2 on held-out instances (test split), at half resolution, 20 target views per object
E="$W/eval-test"
$A eval --run "$W/affnerf" --data "$W/data" --split test --method affnerf,retrieval,constant --scale 0.5 --out "$E" --device "$DEVICE"
$A eval --run "$W/affnerf" --data "$W/data" --split test --method semantic-nerf --scale 0.5 --out "$E" --device "$DEVICE"
$A eval --run "$W/affnerf" --data "$W/data" --split test --method semantic-nerf --input-views 20 --scale 0.5 --out "$E" --device "$DEVICE"
$A eval --run "$W/pixelnerf" --data "$W/data" --split test --method pixelnerf --scale 0.5 --out "$E" --device "$DEVICE"
$A eval --run "$W/pixelnerf" --data "$W/data" --split test --method pixelnerf --input-views 3 --scale 0.5 --out "$E" --device "$DEVICE"

# 4. unseen categories: every instance of the category each leave-one-out run never saw
for held in teapot scissors; do
    U="$W/eval-unseen-$held"
    $A eval --run "$W/loco-$held" --data "$W/data" --split all --categories "$held" --method affnerf,retrieval,constant \
        --scale 0.5 --out "$U" --device "$DEVICE"
    $A eval --run "$W/loco-$held" --data "$W/data" --split all --categories "$held" --method semantic-nerf --scale 0.5 \
        --out "$U" --device "$DEVICE"
done

# 5. Table 3: grasps on the test objects of the paper's four categories
$A eval grasp --run "$W/affnerf" --data "$W/data" --out "$W/grasps" --device "$DEVICE"

# 6. collect
mkdir -p "$R"
cp "$E/table2.md" "$R/table2.md"; cp "$E"/metrics_*.json "$R/" ; cp "$E/figure.png" "$R/table2_figure.png"
for held in teapot scissors; do
    cp "$W/eval-unseen-$held/table2.md" "$R/table2_unseen_$held.md"
    cp "$W/eval-unseen-$held/metrics.json" "$R/metrics_unseen_$held.json"
done
cp "$W/grasps/table3.md" "$R/table3.md"; cp "$W/grasps/grasp_metrics.json" "$R/grasp_metrics.json"
