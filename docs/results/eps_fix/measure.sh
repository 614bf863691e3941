#!/bin/bash
# One candidate of rules.md beside this file on the full Bandai val split (2 replications, DDIM-50, the model's
# guidance): smoothness, FID and accuracy on the action classifier's features.
#   docs/results/eps_fix/measure.sh <checkpoint> <name> [<uniform|leading> <none|static>]
# Writes docs/results/eps_fix/val/<name>.md and .json. Needs data/bandai (make data-full). Without the last two
# arguments the sampler's own timestep spacing and clipping are used. HERE= writes into another study's folder
# (docs/results/geometric_reduction/measure.sh), its runs under outputs/<that folder's name>/val.
set -euo pipefail
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
ckpt=$1; name=$2; here=${HERE:-docs/results/eps_fix}
rules=(); [ $# -ge 4 ] && rules=(timestep_spacing="$3" clip_x0="$4")
out=$here/val; run=outputs/$(basename "$here")/val/$name
mkdir -p "$out"
python evaluate.py checkpoint="$ckpt" dataset=bandai split=val replications=2 mm_replications=0 wandb=false \
  sampler=ddim steps=50 "${rules[@]}" hydra.run.dir="$run"
cp "$run/table.md" "$out/$name.md"; cp "$run/metrics.json" "$out/$name.json"
grep -E "^\| " "$out/$name.md" | head -5
