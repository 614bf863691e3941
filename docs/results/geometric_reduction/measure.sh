#!/bin/bash
# One run of rules.md beside this file on the full Bandai val split (2 replications, DDIM-50, the model's guidance).
#   docs/results/geometric_reduction/measure.sh <checkpoint> <name>      writes val/<name>.md and .json here
set -euo pipefail
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
ckpt=$1; name=$2; out=docs/results/geometric_reduction/val; run=outputs/geometric_reduction/val/$name
mkdir -p "$out"
python evaluate.py checkpoint="$ckpt" dataset=bandai split=val replications=2 mm_replications=0 wandb=false \
  sampler=ddim steps=50 hydra.run.dir="$run"
cp "$run/table.md" "$out/$name.md"; cp "$run/metrics.json" "$out/$name.json"
grep -E "^\| " "$out/$name.md" | head -5
