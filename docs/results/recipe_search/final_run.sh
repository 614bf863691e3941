#!/bin/bash
# The final run of issue 39 (experiment=bandai_text_long), resumed across sittings: from its run folder when this
# machine has one, else from the sitting checkpoint committed beside this script (final_run/last.ckpt: weights, EMA,
# optimizer and data order, so the run goes on exactly where the last sitting stopped; kept out of checkpoints/,
# which the wheel bundles).
# Needs data/bandai (make data-full). Stop a sitting with kill -INT <pid> (Lightning saves nothing on SIGKILL).
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/train/bandai_text_long
train_sitting bandai_text_long $RUN docs/results/recipe_search/final_run/last.ckpt $RUN.sittings.log logger=csv >> /tmp/final.log 2>&1
