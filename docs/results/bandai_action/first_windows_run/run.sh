#!/bin/bash
# Issue 39's third action recipe (experiment=bandai_action_first_windows; rule Z in ../long_run/rules.md), in
# sittings: from its run folder, else from the sitting checkpoint committed beside this script (last.ckpt, when a
# session ends mid-run), else from scratch. Stop a sitting with kill -9 <python pid> (a background job ignores
# SIGINT) after a step checkpoint exists. Needs data/bandai (make data-full).
#   OMP_NUM_THREADS=1 nohup docs/results/bandai_action/first_windows_run/run.sh > outputs/first_windows.log 2>&1 &
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/train/bandai_action_first_windows; HERE=docs/results/bandai_action/first_windows_run
ck=$(resume_arg $RUN $HERE/last.ckpt)
mkdir -p outputs/train
log_sitting $HERE/sittings.log "$ck"
python train.py experiment=bandai_action_first_windows logger=csv hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> $HERE/sittings.log
