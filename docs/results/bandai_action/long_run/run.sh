#!/bin/bash
# Issue 39's action model (experiment=bandai_action_long), resumed across sittings from its run folder, else from the
# sitting checkpoint committed beside this script (long_run/last.ckpt: weights, EMA, optimizer and data order).
# Needs data/bandai (make data-full). Stop a sitting after a step checkpoint with kill -9 <python pid>
# (a background job ignores SIGINT). Rules: rules.md beside this script.
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
RUN=outputs/train/bandai_action_long
SITTING=docs/results/bandai_action/long_run/last.ckpt
if [ ! -f $RUN/checkpoints/last.ckpt ] && [ -f $SITTING ]; then
  mkdir -p $RUN/checkpoints && cp $SITTING $RUN/checkpoints/last.ckpt
fi
ck=""; [ -f $RUN/checkpoints/last.ckpt ] && ck="ckpt_path=$RUN/checkpoints/last.ckpt"
mkdir -p outputs/train
echo "$(date -u +%FT%TZ) sitting starts ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), ${ck:-from scratch})" >> $RUN.sittings.log
python train.py experiment=bandai_action_long logger=csv hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> $RUN.sittings.log
