#!/bin/bash
# Shipping rule S's measurement of one candidate text model (docs/results/shipping/rules.md): the full Bandai val
# split, the project's full-Bandai evaluators, 3 replications, the model's own default guidance, DDIM-50.
#   docs/results/shipping/candidate.sh <checkpoint .ckpt> <table name>   e.g. ... step0049000.ckpt final_run_49000
# Writes docs/results/shipping/val_<today>/<table name>.md (+ _per_action.md); needs data/bandai (make data-full).
set -euo pipefail
cd "$(dirname "$0")/../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
ckpt=$1; name=$2
out=docs/results/shipping/val_$(date -u +%F); run=outputs/shipping/$name
mkdir -p "$out"
python evaluate.py checkpoint="$ckpt" dataset=bandai split=val replications=3 mm_replications=0 wandb=false \
  hydra.run.dir="$run"
cp "$run/table.md" "$out/$name.md"
[ -f "$run/action_accuracy.md" ] && cp "$run/action_accuracy.md" "$out/${name}_per_action.md"
grep -E "^\| (Real|bandai)" "$out/$name.md"
