#!/bin/bash
# Issue 39's second action recipe (experiment=bandai_action_trans_dec; rules.md beside this script), in sittings: from
# its run folder, else from the sitting checkpoint committed beside this script (last.ckpt, when a session ends
# mid-run), else from scratch. Stop a sitting with kill -9 <python pid> (a background job ignores SIGINT) after a
# step checkpoint exists. Needs data/bandai (make data-full).
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/train/bandai_action_trans_dec; HERE=docs/results/bandai_action/trans_dec_run
train_sitting bandai_action_trans_dec $RUN $HERE/last.ckpt $HERE/sittings.log logger=csv
