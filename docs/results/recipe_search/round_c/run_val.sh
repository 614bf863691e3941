#!/bin/bash
# Round C (rules.md), second half: val label captions (2 replications, DDIM-50, the model's guidance) per mapping.
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate
for m in none nearest vote; do
  python evaluate.py checkpoint=shipped dataset=bandai split=val replications=2 mm_replications=0 wandb=false \
    prompt_mapping=$m hydra.run.dir=outputs/round_c/val_$m
done
