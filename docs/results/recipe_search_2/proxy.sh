#!/bin/bash
# One proxy of rules.md beside this file, trained and then measured on val (resumes from its run folder).
#   docs/results/recipe_search_2/proxy.sh F0|F1
# F0: data/bandai (plain wording); F1: data/bandai_broad (prepare it first:
#   python -m motiondiff.data.preparing.prepare bandai --src <ds1.zip> --src <ds2.zip> --out data/bandai_broad
#     --seed 0 --caption-wording broad --held-out data/paraphrases/<each human-style set>.json)
set -euo pipefail
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
name=$1; here=docs/results/recipe_search_2; run=outputs/recipe_search_2/$name
case $name in F0) root=data/bandai;; F1) root=data/bandai_broad;; *) echo "F0 or F1, got $name"; exit 2;; esac
ck=$(resume_arg $run ""); mkdir -p outputs/recipe_search_2 $here/$name
if [ ! -f $run/checkpoints/step0004000.ckpt ]; then
  log_sitting $run.sittings.log "$ck"
  python train.py experiment=bandai_text_finetune dataset.root=$root logger=csv hydra.run.dir=$run $ck
  echo "$(date -u +%FT%TZ) sitting ends" >> $run.sittings.log
fi
ckpt=$run/checkpoints/step0004000.ckpt
[ -f $run/val/table.md ] || python evaluate.py checkpoint=$ckpt dataset=bandai split=val replications=2 \
  mm_replications=0 wandb=false sampler=ddim steps=50 guidance=2 hydra.run.dir=$run/val
cp $run/val/table.md $here/$name/val.md; cp $run/val/action_accuracy.md $here/$name/val_per_action.md
[ -f $run/human_val/paraphrases.md ] || python -m motiondiff.studies.action_accuracy checkpoint=$ckpt \
  captions=data/paraphrases/bandai_human_val.json num_samples=5 sampler=ddim steps=50 guidance=2 out=$run/human_val
cp $run/human_val/paraphrases.md $here/$name/human_val.md
grep -E "^\| bandai|accuracy over" $here/$name/val.md $here/$name/human_val.md
