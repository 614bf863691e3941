#!/bin/bash
# Rule G of rules.md beside this file: F0's fine-tune to 20,000 steps, in sittings. A sitting resumes from the run
# folder, else from the committed sitting checkpoint g_last.ckpt beside this script. Stop it with kill -9 <python
# pid> (a background job ignores SIGINT): the last checkpoint (every 500 steps) is where the next sitting starts.
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/recipe_search_2/G
ck=$(resume_arg $RUN docs/results/recipe_search_2/g_last.ckpt)
mkdir -p outputs/recipe_search_2
log_sitting docs/results/recipe_search_2/g_sittings.log "$ck"
python train.py experiment=bandai_text_finetune trainer.max_steps=20000 logger=csv hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> docs/results/recipe_search_2/g_sittings.log
