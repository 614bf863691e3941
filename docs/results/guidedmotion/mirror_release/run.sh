#!/bin/bash
# GuidedMotion with mirroring (issues 39 point 7 and 43 point 3): `make guided-compare`'s CPU recipe (three motion
# VAEs, then the latent stage) with every train clip also left-right mirrored, in sittings: a stage whose run.json has
# no train_steps yet resumes from its last.ckpt; a finished stage is skipped. Stop a sitting with kill -INT <pid>
# (Lightning saves on SIGINT). Each sitting appends a line (machine, start) to $GC.sittings.log.
# Afterwards `make guided-compare GC=$GC GC_MIRROR=true` trains MDM for the same time and writes the comparison.
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
GC=${GC:-outputs/guided_mirror}
COMP="dataset=bandai_mini_compositional dataset.datamodule.mirror=true logger=csv"
finished() { python -c "import json,sys; sys.exit(0 if 'train_steps' in json.load(open('$1/run.json')) else 1)" 2>/dev/null; }
resume() { [ -f $1/checkpoints/last.ckpt ] && echo "ckpt_path=$1/checkpoints/last.ckpt"; }
mkdir -p $GC
echo "$(date -u +%FT%TZ) sitting starts ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs))" >> $GC.sittings.log
for level in motion action specific; do
  run=$GC/vae_$level; finished $run && continue
  python train_vae.py level=$level $COMP batch_size=16 optim.lr=5e-4 trainer.max_steps=960 \
    trainer.check_val_every_n_epoch=5 checkpoint_every=240 hydra.run.dir=$run $(resume $run) || exit 1
done
run=$GC/latent
finished $run || python train_latent.py vae.motion=$GC/vae_motion/checkpoints/last.ckpt \
  vae.action=$GC/vae_action/checkpoints/last.ckpt vae.specific=$GC/vae_specific/checkpoints/last.ckpt $COMP \
  batch_size=32 optim.lr=2e-4 optim.schedule=cosine optim.warmup_steps=200 trainer.max_steps=5000 \
  checkpoint_every=250 hydra.run.dir=$run $(resume $run) || exit 1
echo "$(date -u +%FT%TZ) all stages finished" >> $GC.sittings.log
