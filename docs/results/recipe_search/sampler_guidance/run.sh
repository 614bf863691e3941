#!/bin/bash
# Step 2 of "The run's end" (docs/results/recipe_search/rules.md): the shipped text model's default sampler and
# guidance, chosen on val. Guidance 1, 1.5, 2, 3 x DDIM-50 and DPM-Solver++(2M)-10, full val split, 2 replications.
#   docs/results/recipe_search/sampler_guidance/run.sh <model (.ckpt or .safetensors)>
# Writes one table per pair beside this script and summary.md (the rule's pick); needs data/bandai (make data-full).
# HERE= and OUT= send the tables and the runs elsewhere (recipe 2: docs/results/recipe_search_2/sampler_guidance.sh).
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
model=$1; here=${HERE:-docs/results/recipe_search/sampler_guidance}; out=${OUT:-outputs/sampler_guidance}
for sampler in "ddim 50" "dpmpp 10"; do
  set -- $sampler
  for g in 1 1.5 2 3; do
    name=${1}${2}_g$g; run=$out/$name
    [ -f "$run/metrics.json" ] || python evaluate.py checkpoint="$model" dataset=bandai split=val replications=2 \
      mm_replications=0 sampler=$1 steps=$2 guidance=$g wandb=false hydra.run.dir="$run" > /tmp/sg_$name.log 2>&1
    cp "$run/table.md" "$here/$name.md"
  done
done
python docs/results/recipe_search/sampler_guidance/pick.py "$out" > "$here/summary.md"
cat "$here/summary.md"
