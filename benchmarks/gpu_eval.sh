#!/usr/bin/env bash
# The shipped model's 2D tables on one lent GPU machine, in one command that fits a 10-minute slot (issue 12):
# Table 2 at 200x150 (test split, 5 objects per category, 20 targets; affnerf, affnerf-fit, retrieval, constant),
# the baselines' shared protocol (2 objects per category, 5 targets at 200x150) and view stability (every test object
# from 4 input-view sets, 10 targets at 100x75, meshes at 96^3): the protocols of
# reproduce_tables.sh, one process per category side by side (objects are evaluated independently), each folder
# merged afterwards by benchmarks/merge_eval.py. It first runs the CUDA-only tests. PROTOCOLS picks among those three;
# UNSEEN="teapot=RUN1 scissors=RUN2" adds the unseen-category protocols of leave-one-category-out runs (the first 10
# instances of the held-out category, 20 targets at 200x150 with affnerf-fit; the first 4, 5 targets, as the baselines'
# shared protocol), one process per held-out category.
#
#   RUN=src/affnerf/weights/affnerf-small.pt bash benchmarks/gpu_eval.sh
#
# On the 2-core CPU machine (how the tables of 2026-11-28 were made: 46 minutes for table2 and base, niced beside a
# training on the other core; table2 alone again with 3D on outer surfaces, beside a demo run, 71 minutes):
#   PY=.venv/bin/python DEVICE=cpu GPU_THREADS=1 DATA=DATA PROTOCOLS="table2 base" bash benchmarks/gpu_eval.sh
#
# Writes $OUT/device.txt, $OUT/tests.log and $OUT/gpu_eval.tar.gz (one folder per protocol and category, logs). A
# second call on the same machine can reuse the dataset: DATA=<first WORK>/data.
# Needs python3 with CUDA torch, and the wheels of trimesh, embreex, shapely, mapbox-earcut, rtree, tyro,
# docstring-parser, typeguard and shtab in .whl/ when the machine lacks them (benchmarks/README.md). A category whose
# CUDA evaluation fails is evaluated again on the CPU (its log says so).
set -uo pipefail
cd "$(dirname "$0")/.."
RUN="${RUN:-src/affnerf/weights/affnerf-small.pt}"
W="${WORK:-/tmp/gpu}"
OUT="${OUT:-$W/out}"
PY="${PY:-python3}"
DEVICE="${DEVICE:-cuda}"
OBJECTS="${OBJECTS:-80}"    # objects per category (80: the dataset of every committed table)
WORKERS="${WORKERS:-16}"    # data generation processes
CATS="${CATS:-screwdriver pen scissors eyeglasses bucket bottle cabinet teapot}"
PROTOCOLS="${PROTOCOLS:-table2 base stability}"
STABILITY_OBJECTS="${STABILITY_OBJECTS:-8}"  # test objects per category predicted from 4 input-view sets (8: all)
UNSEEN="${UNSEEN:-}"
mkdir -p "$W" "$OUT"

GPU_THREADS=2
# shellcheck source=benchmarks/gpu_env.sh
source benchmarks/gpu_env.sh
D="${DATA:-$W/data}"

# ev RUN OUT-FOLDER OPTIONS...: one `affnerf eval` on $DEVICE, again on the CPU if that fails
ev() {
    local run=$1 out=$2
    shift 2
    A eval --run "$run" --data "$D" --out "$out" "$@" --device "$DEVICE" --chunk 16384 ||
        { echo "eval on $DEVICE failed ($*): again on the CPU"; A eval --run "$run" --data "$D" --out "$out" "$@" --device cpu; }
}

# one category: the protocols of $PROTOCOLS, one after the other
category() {
    local c=$1
    case " $PROTOCOLS " in *" table2 "*)
        ev "$RUN" "$W/table2/$c" --split test --categories "$c" --method affnerf,retrieval,constant --scale 0.5 \
            --target-views 20 --max-objects 5
        ev "$RUN" "$W/table2/$c" --split test --categories "$c" --method affnerf-fit --scale 0.5 --target-views 20 \
            --max-objects 5 ;;
    esac
    case " $PROTOCOLS " in *" base "*)
        ev "$RUN" "$W/base/$c" --split test --categories "$c" --method affnerf,retrieval,constant --scale 0.5 \
            --target-views 5 --max-objects 2 ;;
    esac
    case " $PROTOCOLS " in *" stability "*)
        ev "$RUN" "$W/stability/$c" --split test --categories "$c" --method affnerf,affnerf-fit,retrieval \
            --target-views 10 --scale 0.25 --max-objects "$STABILITY_OBJECTS" --mesh-resolution 96 --stability-views 4 ;;
    esac
    echo "$c done at $(elapsed) s"
}

# unseen HELD RUN: a leave-one-category-out run on the category it never saw
unseen() {
    local held=$1 run=$2
    ev "$run" "$W/unseen/$held" --split all --categories "$held" --method affnerf,affnerf-fit,retrieval,constant \
        --scale 0.5 --target-views 20 --max-objects 10
    ev "$run" "$W/unseen-base/$held" --split all --categories "$held" --method affnerf,retrieval,constant --scale 0.5 \
        --target-views 5 --max-objects 4
    echo "unseen $held done at $(elapsed) s"
}

{
    nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv 2>&1
    "$PY" -c "import torch; print('torch', torch.__version__, 'cuda', torch.cuda.is_available())"
    nproc
} > "$OUT/device.txt"
"$PY" -m pytest -q -p no:cacheprovider tests/model/test_model.py -k gpu > "$OUT/tests.log" 2>&1 &
[ -f "$D/dataset.json" ] || A data generate --out "$D" --objects-per-category "$OBJECTS" --views 30 \
    --workers "$WORKERS" --seed 0 > "$W/data.log" 2>&1
echo "data at $(elapsed) s" | tee -a "$OUT/device.txt"
wait
if [ -n "$PROTOCOLS" ]; then
    for c in $CATS; do
        category "$c" > "$W/eval-$c.log" 2>&1 &
    done
fi
for pair in $UNSEEN; do
    unseen "${pair%%=*}" "${pair#*=}" > "$W/eval-unseen-${pair%%=*}.log" 2>&1 &
done
wait
echo "evaluations done at $(elapsed) s" | tee -a "$OUT/device.txt"
tail -n 3 "$W"/eval-*.log
tar -czf "$OUT/gpu_eval.tar.gz" -C "$W" $(cd "$W" && ls -d table2 base stability unseen unseen-base data.log eval-*.log 2>/dev/null)
