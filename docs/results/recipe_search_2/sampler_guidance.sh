#!/bin/bash
# Rule F's step after a ship (rules.md beside this file): the shipped candidate's default sampler and guidance on val,
# exactly as the first recipe chose them (docs/results/recipe_search/sampler_guidance/run.sh: guidance 1, 1.5, 2, 3 x
# DDIM-50 and DPM-Solver++(2M)-10, full val split, 2 replications, seed 0; its pick.py: the highest val action
# accuracy, within 0.01 the lower FID), here with its tables and runs kept apart. A proxy's own val run (F0, F1) is
# the DDIM-50 / guidance 2 row (the same settings), so it is not run again; G has none and runs all eight.
#   docs/results/recipe_search_2/sampler_guidance.sh F0|F1|G
set -euo pipefail
cd "$(dirname "$0")/../../.."
name=$1; export HERE=docs/results/recipe_search_2/sampler_guidance_$name OUT=outputs/recipe_search_2/sampler_guidance_$name
ckpt=outputs/recipe_search_2/$name/checkpoints/step0004000.ckpt
[ "$name" = G ] && ckpt=outputs/recipe_search_2/G/checkpoints/step0020000.ckpt
mkdir -p $HERE $OUT/ddim50_g2
[ -f outputs/recipe_search_2/$name/val/metrics.json ] && \
  cp outputs/recipe_search_2/$name/val/metrics.json outputs/recipe_search_2/$name/val/table.md $OUT/ddim50_g2/
docs/results/recipe_search/sampler_guidance/run.sh $ckpt
