#!/bin/bash
# Issue 39's action model (experiment=bandai_action_long), resumed across sittings from its run folder, else from the
# sitting checkpoint once committed beside this script (long_run/last.ckpt; removed after the run ended at 20,000).
# Needs data/bandai (make data-full). Stop a sitting after a step checkpoint with kill -9 <python pid>
# (a background job ignores SIGINT). Rules: rules.md beside this script.
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/train/bandai_action_long; HERE=docs/results/bandai_action/long_run
train_sitting bandai_action_long $RUN $HERE/last.ckpt $RUN.sittings.log logger=csv
