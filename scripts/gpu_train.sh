#!/usr/bin/env bash
# The one prepared command for a lent GPU (device tool): the `small` preset (about 4 x the `cpu`
# one's parameters) with the current training defaults, without the M2D validation clips
# (--hold-out-validation: settings are chosen on them, docs/sgmd.md), for as many steps as fit in ~9 minutes;
# the checkpoint is written to $OUT (or runs/gpu), to bring back and score here with
# scripts/evaluate_sgmd.py.
#
#   scripts/gpu_train.sh [DATA] [STEPS]      # DATA: ../shared/data/m2d or shared/data/m2d
#
# The device machine has no network: it runs the checkout with its own python3 and torch
# (PYTHONPATH, no install); packages it lacks (typer, librosa, soundfile, rich...) travel as
# wheels in .whl/ as /work/.library/device/README.md describes. Unverified so far: no GPU has
# been lent to this project.
set -euo pipefail
data=${1:-$( [ -d shared/data/m2d ] && echo shared/data/m2d || echo ../shared/data/m2d )}
steps=${2:-6000}
out=${OUT:-runs/gpu}
if [ -d .whl ]; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
  export PYTHONPATH=/tmp/site
fi
export PYTHONPATH=src:generators:${PYTHONPATH:-} PYTHONUNBUFFERED=1
choreo() { python3 -c "import sys; from choreo.cli import main; sys.exit(main())" "$@"; }
choreo prepare "$data"
timeout 540 python3 -c "import sys; from choreo.cli import main; sys.exit(main())" train sgmd --data "$data" \
  --out "$out" --config small --steps "$steps" --batch-size 64 --checkpoint-every 500 --hold-out-validation || true  # time limit: last.pt stays
ls -l "$out"
