#!/bin/bash
# Issue 39's third action recipe (experiment=bandai_action_first_windows; rule Z in ../long_run/rules.md), in
# sittings: from its run folder, else from a sitting checkpoint committed beside this script (last.ckpt, while a
# session ends mid-run; removed once the run ended at 20,000), else from scratch. Its two rule-Z candidates' EMA
# weights are kept beside it (candidate_*.safetensors + JSON; not releases). Stop a sitting with kill -9 <python pid>
# (a background job ignores SIGINT) after a step checkpoint exists. Needs data/bandai (make data-full).
#   OMP_NUM_THREADS=1 nohup docs/results/bandai_action/first_windows_run/run.sh > outputs/first_windows.log 2>&1 &
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/train/bandai_action_first_windows; HERE=docs/results/bandai_action/first_windows_run
train_sitting bandai_action_first_windows $RUN $HERE/last.ckpt $HERE/sittings.log logger=csv
