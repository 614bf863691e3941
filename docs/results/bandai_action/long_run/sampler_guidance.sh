#!/bin/bash
# rules.md's guidance and sampler step for the action model that is shipped: guidance 1, 2, 3 with DDIM-50, then
# DPM-Solver++-10 at the guidance given as the second argument (the DDIM winner), 2 replications each, full val split.
#   docs/results/bandai_action/long_run/sampler_guidance.sh <checkpoint> ddim      # the three DDIM-50 runs
#   docs/results/bandai_action/long_run/sampler_guidance.sh <checkpoint> <g>       # DPM-Solver++-10 at guidance g
# Writes docs/results/bandai_action/long_run/val/sg_<sampler>_g<g>.md. Needs data/bandai (make data-full).
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
ckpt=$1; what=$2; out=docs/results/bandai_action/long_run/val
one() {  # sampler steps guidance
  local name=sg_$1_g$3 run=outputs/action_val/sg_$1_g$3
  python evaluate.py checkpoint="$ckpt" dataset=bandai split=val replications=2 mm_replications=0 wandb=false \
    sampler=$1 steps=$2 guidance=$3 hydra.run.dir="$run"
  cp "$run/table.md" "$out/$name.md"; grep -E "^\| " "$out/$name.md" | head -4
}
if [ "$what" = ddim ]; then for g in 1 2 3; do one ddim 50 $g; done; else one dpmpp 10 "$what"; fi
