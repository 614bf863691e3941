#!/bin/bash
# The final run of issue 39 (experiment=bandai_text_long), resumed across sittings: from its run folder when this
# machine has one, else from the sitting checkpoint committed beside this script (final_run/last.ckpt: weights, EMA,
# optimizer and data order, so the run goes on exactly where the last sitting stopped; kept out of checkpoints/,
# which the wheel bundles).
# Needs data/bandai (make data-full). Stop a sitting with kill -INT <pid> (Lightning saves nothing on SIGKILL).
cd "$(dirname "$0")/../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
RUN=outputs/train/bandai_text_long
SITTING=docs/results/recipe_search/final_run/last.ckpt
if [ ! -f $RUN/checkpoints/last.ckpt ] && [ -f $SITTING ]; then
  mkdir -p $RUN/checkpoints && cp $SITTING $RUN/checkpoints/last.ckpt
fi
ck=""; [ -f $RUN/checkpoints/last.ckpt ] && ck="ckpt_path=$RUN/checkpoints/last.ckpt"
echo "$(date -u +%FT%TZ) sitting starts ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), ${ck:-from scratch})" >> $RUN.sittings.log
python train.py experiment=bandai_text_long logger=csv hydra.run.dir=$RUN $ck >> /tmp/final.log 2>&1
