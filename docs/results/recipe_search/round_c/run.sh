#!/bin/bash
# Round C (rules.md): the shipped model on the human-style val set and on val label captions, per prompt mapping.
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate
OUT=outputs/round_c
for m in none nearest vote; do
  python -m motiondiff.studies.action_accuracy checkpoint=shipped captions=data/paraphrases/bandai_human_val.json \
    num_samples=5 prompt_mapping=$m out=$OUT/human_val_$m
done
