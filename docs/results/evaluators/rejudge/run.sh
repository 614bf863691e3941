#!/bin/bash
# Rule E2's second half (docs/results/evaluators/bandai_action_v2.md): every number the open rules compare, measured
# again with the new released action classifier (checkpoints/evaluators/bandai/action.*), beside the old numbers
# (the old classifier is kept in docs/results/evaluators/bandai_action_v1/). Each step is skipped when its output
# exists, so the script resumes after an interruption. Needs data/bandai (make data-full).
#   docs/results/evaluators/rejudge/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
here=docs/results/evaluators/rejudge; out=outputs/rejudge; old=docs/results/evaluators/bandai_action_v1
mkdir -p $out
# 1. The text shipping rule S (docs/results/shipping/rules.md): the shipped 42k model against the final run's end,
#    with the sampler their old numbers used (val_2026-12-05/final_run_42000.md, val_2026-12-06/final_run_97000.md).
for c in "shipped shipped_42k" "docs/results/recipe_search/final_run/last.ckpt final_run_97000"; do
  set -- $c; o=$out/text_$2
  [ -f $o/table.md ] || python evaluate.py checkpoint=$1 dataset=bandai split=val replications=3 \
    mm_replications=0 wandb=false sampler=ddim steps=50 guidance=2 hydra.run.dir=$o > $o.log 2>&1
  cp $o/table.md $here/text_$2.md; [ -f $o/action_accuracy.md ] && cp $o/action_accuracy.md $here/text_$2_per_action.md
done
# 2. The shipped text model on the two held-out human-style sets, judged by the new and by the old classifier (the
#    same seed, so the same motions up to float differences between CPUs).
for set in bandai_human bandai_human_2; do
  for judge in new old; do
    o=$out/${set}_$judge; ev=""; [ $judge = old ] && ev="evaluators=$old"
    [ -f $o/paraphrases.md ] || python -m motiondiff.studies.action_accuracy checkpoint=shipped \
      captions=data/paraphrases/$set.json num_samples=5 out=$o $ev > $o.log 2>&1
    mkdir -p $here/${set}_$judge && cp $o/*.md $here/${set}_$judge/
  done
done
# 3. The behaviour study of the shipped text model (its verdicts come from the classifier).
o=$out/behaviour
[ -f $o/behaviour.md ] || python -m motiondiff.studies.behaviour checkpoint=shipped out=$o > $o.log 2>&1
mkdir -p $here/behaviour && cp $o/*.md $here/behaviour/
# 4. The action model's ship rule (docs/results/bandai_action/long_run/rules.md): released, best, last; val.
for c in "checkpoints/models/bandai_action_cpu.safetensors released" \
         "outputs/train/bandai_action_long/checkpoints/best-fid-step0009800.ckpt best_9800" \
         "outputs/train/bandai_action_long/checkpoints/last.ckpt last_20000"; do
  set -- $c; o=$out/action_$2
  [ -f $o/table.md ] || python evaluate.py checkpoint=$1 dataset=bandai split=val replications=3 \
    mm_replications=0 wandb=false sampler=ddim steps=50 guidance=2 hydra.run.dir=$o > $o.log 2>&1
  cp $o/table.md $here/action_$2.md
done
echo done
