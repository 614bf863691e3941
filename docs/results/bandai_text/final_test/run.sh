#!/bin/bash
# Step 3 of "The run's end" (docs/results/recipe_search/rules.md), run once: the shipped text model on the full
# Bandai test split (20 replications, its own default sampler, steps and guidance), the two held-out human-style
# sets (5 samples per description) and the behaviour study. Needs data/bandai (make data-full).
#   docs/results/bandai_text/final_test/run.sh <sampler> <steps>      (the release's own: see its JSON)
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
here=docs/results/bandai_text/final_test; sampler=$1; steps=$2
run=outputs/final_test/test_r20
[ -f $run/metrics.json ] || python evaluate.py checkpoint=shipped dataset=bandai split=test replications=20 \
  mm_replications=0 sampler=$sampler steps=$steps wandb=false hydra.run.dir=$run > /tmp/final_test.log 2>&1
cp $run/table.md $here/test_r20.md; cp $run/action_accuracy.md $here/test_r20_per_action.md
cp $run/metrics.json $here/test_r20_metrics.json
for set in bandai_human bandai_human_2; do
  out=outputs/final_test/$set
  [ -f $out/paraphrases.md ] || python -m motiondiff.studies.action_accuracy checkpoint=shipped \
    captions=data/paraphrases/$set.json num_samples=5 out=$out > /tmp/final_$set.log 2>&1
  mkdir -p $here/$set && cp $out/*.md $out/*.png $here/$set/ 2>/dev/null || true
done
out=outputs/final_test/behaviour
[ -f $out/behaviour.md ] || python -m motiondiff.studies.behaviour checkpoint=shipped out=$out > /tmp/final_behaviour.log 2>&1
mkdir -p $here/behaviour && cp $out/*.md $out/*.png $here/behaviour/ 2>/dev/null || true
grep -E "^\| (Real|bandai)" $here/test_r20.md
