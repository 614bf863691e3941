#!/bin/bash
# Rule E2's check V and the second judge (docs/results/evaluators/bandai_action_v2.md): the balanced action
# classifier of rule E2 (docs/results/evaluators/bandai_action_v3/) judging what the shipped text model makes,
# beside the released classifier (checkpoints/evaluators/bandai). Each step is skipped when its output exists.
# Needs data/bandai (make data-full).
#   docs/results/evaluators/rejudge/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
here=docs/results/evaluators/rejudge; out=outputs/rejudge; v3=docs/results/evaluators/bandai_action_v3
judge=$out/evaluators_v3   # the v3 action classifier beside the released text-motion evaluator
mkdir -p $judge && cp $v3/action.* checkpoints/evaluators/bandai/text_motion.* $judge/
# Check V: the shipped model's val motions from label captions (the sampling of
# docs/results/shipping/val_2026-12-05/final_run_42000.md, so the same motions its released-classifier numbers judged).
o=$out/text_shipped_42k
[ -f $o/table.md ] || python evaluate.py checkpoint=shipped dataset=bandai split=val replications=3 mm_replications=0 \
  wandb=false sampler=ddim steps=50 guidance=2 evaluator_dir=$judge hydra.run.dir=$o > $o.log 2>&1
mkdir -p $here/check_v && cp $o/table.md $here/check_v/shipped_42k_val_new_classifier.md
cp $o/action_accuracy.md $here/check_v/shipped_42k_val_new_classifier_per_action.md
# The second judge on the two held-out human-style sets (the shipped model's own sampling, 5 samples each), beside
# the released classifier on the same motions.
for set in bandai_human bandai_human_2; do
  for j in released v3; do
    o=$out/${set}_$j; ev=""; [ $j = v3 ] && ev="evaluators=$v3"
    [ -f $o/paraphrases.md ] || python -m motiondiff.studies.action_accuracy checkpoint=shipped \
      captions=data/paraphrases/$set.json num_samples=5 out=$o $ev > $o.log 2>&1
    mkdir -p $here/${set}_$j && cp $o/paraphrases.md $here/${set}_$j/
  done
done
