#!/bin/bash
# Issue 39's second action recipe (experiment=bandai_action_trans_dec; rules.md beside this script), in sittings: from
# its run folder, else from the sitting checkpoint committed beside this script (last.ckpt, when a session ends
# mid-run), else from scratch. Stop a sitting with kill -9 <python pid> (a background job ignores SIGINT) after a
# step checkpoint exists. Needs data/bandai (make data-full).
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/train/bandai_action_trans_dec; LOG=docs/results/bandai_action/trans_dec_run/sittings.log
ck=$(resume_arg $RUN docs/results/bandai_action/trans_dec_run/last.ckpt)
mkdir -p outputs/train
log_sitting $LOG "$ck"
python train.py experiment=bandai_action_trans_dec logger=csv hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> $LOG
