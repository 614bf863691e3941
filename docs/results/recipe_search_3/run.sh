#!/bin/bash
# Run H of rules.md beside this file (experiment=bandai_text_trans_dec), in sittings: from its run folder when this
# machine has one, else from the sitting checkpoint committed beside this script (h_last.ckpt, when a session ends
# mid-run), else afresh from init_trans_dec_step15000.safetensors. Stop a sitting with kill -9 <python pid> (a
# background job ignores SIGINT) after a step checkpoint (one after each 1,000-step evaluation) exists.
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/recipe_search_3/H; LOG=docs/results/recipe_search_3/sittings.log
ck=$(resume_arg $RUN docs/results/recipe_search_3/h_last.ckpt)
mkdir -p outputs/recipe_search_3
log_sitting $LOG "$ck"
python train.py experiment=bandai_text_trans_dec logger=csv hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> $LOG
