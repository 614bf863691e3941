#!/bin/bash
# Rule F's step after a ship (rules.md beside this file): the shipped candidate's default sampler and guidance on val,
# exactly as the first recipe chose them (docs/results/recipe_search/sampler_guidance/: guidance 1, 1.5, 2, 3 x
# DDIM-50 and DPM-Solver++(2M)-10, full val split, 2 replications, seed 0; its pick.py: the highest val action
# accuracy, within 0.01 the lower FID). The proxy's own val run is the DDIM-50 / guidance 2 row (same settings).
#   docs/results/recipe_search_2/sampler_guidance.sh F0|F1
set -euo pipefail
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
name=$1; model=outputs/recipe_search_2/$name/checkpoints/step0004000.ckpt
here=docs/results/recipe_search_2/sampler_guidance; out=outputs/recipe_search_2/sampler_guidance_$name
mkdir -p $here $out/ddim50_g2; cp outputs/recipe_search_2/$name/val/metrics.json outputs/recipe_search_2/$name/val/table.md $out/ddim50_g2/
for sampler in "ddim 50" "dpmpp 10"; do
  set -- $sampler
  for g in 1 1.5 2 3; do
    n=${1}${2}_g$g; run=$out/$n
    [ -f "$run/metrics.json" ] || python evaluate.py checkpoint="$model" dataset=bandai split=val replications=2 \
      mm_replications=0 sampler=$1 steps=$2 guidance=$g wandb=false hydra.run.dir="$run" > $out/$n.log 2>&1
    cp "$run/table.md" "$here/$n.md"
  done
done
python docs/results/recipe_search/sampler_guidance/pick.py $out > "$here/summary.md"
cat "$here/summary.md"
