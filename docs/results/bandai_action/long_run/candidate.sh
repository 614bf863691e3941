#!/bin/bash
# The ship rule's measurement of one action model (rules.md beside this file): the full Bandai val split, the
# action classifier's features, 3 replications, DDIM-50, guidance 2 (extra key=value arguments go to evaluate.py).
#   docs/results/bandai_action/long_run/candidate.sh <.ckpt or release> <table name> [key=value ...]
# Writes docs/results/bandai_action/long_run/val/<table name>.md; needs data/bandai (make data-full).
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
ckpt=$1; name=$2; shift 2
out=docs/results/bandai_action/long_run/val; run=outputs/action_val/$name
mkdir -p "$out"
python evaluate.py checkpoint="$ckpt" dataset=bandai split=val replications=3 mm_replications=0 wandb=false \
  sampler=ddim steps=50 guidance=2 "$@" hydra.run.dir="$run"
cp "$run/table.md" "$out/$name.md"
grep -E "^\| " "$out/$name.md" | head -5
