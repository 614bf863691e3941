#!/bin/bash
# The measurement of README.md's rule: DDIM-50 x 5 replications against DPM-Solver++(2M)-10 x 20 on the Bandai val
# split, the shipped text model, one process after the other on the same machine (needs data/bandai: make data-full).
set -euo pipefail
cd "$(dirname "$0")/../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
common="checkpoint=shipped dataset=bandai split=val mm_replications=0 guidance=2 wandb=false"  # the rule's guidance (2), written when it was the default
for run in "ddim50_r5 replications=5" "dpmpp10_r20 replications=20 sampler=dpmpp steps=10"; do
  name=${run%% *}; args=${run#* }
  [ -f outputs/evaluate/speed_$name/metrics.json ] || python evaluate.py $common $args \
    hydra.run.dir=outputs/evaluate/speed_$name > /tmp/speed_$name.log 2>&1
done
grep -h "whole evaluation" /tmp/speed_*.log || true
