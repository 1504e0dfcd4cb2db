# Sourced by the scripts that run on a lent GPU machine (gpu_*.sh), from the checkout's root: installs the wheels
# carried in .whl/ when the machine's python ($PY) lacks affnerf's dependencies (benchmarks/README.md), puts src/ on
# the path, and defines A, affnerf's command line under $PY (AFF, the same as an array). OMP_NUM_THREADS defaults to
# GPU_THREADS (4). The script's clock starts here: elapsed prints its seconds.
# shellcheck shell=bash
T0=$(date +%s)
elapsed() { echo $(($(date +%s) - T0)); }
export PYTHONPATH="$PWD/src:/tmp/site${PYTHONPATH:+:$PYTHONPATH}"
if [ -d .whl ] && ! "$PY" -c "import trimesh, embreex, tyro" 2>/dev/null; then  # (a warm machine has them)
    "$PY" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
fi
export PYTHONUNBUFFERED=1 OMP_NUM_THREADS="${OMP_NUM_THREADS:-${GPU_THREADS:-4}}"
AFF=("$PY" -c 'import sys; from affnerf.cli.main import main; sys.exit(main())')
A() { "${AFF[@]}" "$@"; }
