#!/bin/bash
# GuidedMotion with mirroring (issues 39 point 7 and 43 point 3): the CPU recipe of docs/guidedmotion.md (three
# motion VAEs, then latent diffusion) with every train clip also left-right mirrored, in sittings: a stage whose
# run.json has no train_steps yet resumes from its last.ckpt; a finished stage is skipped.
#   latent_v: the documented CPU recipe (v prediction), released as checkpoints/models/bandai_guided_cpu;
#   latent:   the paper's ε prediction, what `make guided-compare` compares with MDM (it runs this script).
# Stop a sitting after a step checkpoint with kill -9 <python pid> (a background job ignores SIGINT).
# Each sitting appends a line (machine, start) to $GC.sittings.log.
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
GC=${GC:-outputs/guided_mirror}
LATENTS=${LATENTS:-latent_v latent}
COMP="dataset=bandai_mini_compositional dataset.datamodule.mirror=true logger=csv"
finished() { python -c "import json,sys; sys.exit(0 if 'train_steps' in json.load(open('$1/run.json')) else 1)" 2>/dev/null; }
mkdir -p $GC
log_sitting $GC.sittings.log "stages resume from their last.ckpt"
for level in motion action specific; do
  run=$GC/vae_$level; finished $run && continue
  python train_vae.py level=$level $COMP batch_size=16 optim.lr=5e-4 trainer.max_steps=960 \
    trainer.check_val_every_n_epoch=5 checkpoint_every=240 hydra.run.dir=$run $(resume_arg $run) || exit 1
done
for stage in $LATENTS; do
  run=$GC/$stage; finished $run && continue
  prediction=eps; [ $stage = latent_v ] && prediction=v
  python train_latent.py vae.motion=$GC/vae_motion/checkpoints/last.ckpt \
    vae.action=$GC/vae_action/checkpoints/last.ckpt vae.specific=$GC/vae_specific/checkpoints/last.ckpt $COMP \
    batch_size=32 optim.lr=2e-4 optim.schedule=cosine optim.warmup_steps=200 trainer.max_steps=5000 \
    diffusion.prediction=$prediction checkpoint_every=250 hydra.run.dir=$run $(resume_arg $run) || exit 1
done
echo "$(date -u +%FT%TZ) stages finished: $LATENTS" >> $GC.sittings.log
