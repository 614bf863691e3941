#!/bin/bash
# The final run of issue 39 (experiment=bandai_text_long), resumed from its run folder when one exists.
cd "$(dirname "$0")/../../.."; source .venv/bin/activate
export LD_PRELOAD=/usr/lib/x86_64-linux-gnu/libtcmalloc_minimal.so.4
RUN=outputs/train/bandai_text_long
ck=""; [ -f $RUN/checkpoints/last.ckpt ] && ck="ckpt_path=$RUN/checkpoints/last.ckpt"
python train.py experiment=bandai_text_long logger=csv hydra.run.dir=$RUN $ck >> /tmp/final.log 2>&1
