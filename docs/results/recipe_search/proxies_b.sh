#!/bin/bash
# usage: proxiesB.sh <winner run name> <steps> [winner's overrides...]
cd /work/main; source .venv/bin/activate
export LD_PRELOAD=/usr/lib/x86_64-linux-gnu/libtcmalloc_minimal.so.4
WIN=$1; STEPS=$2; shift 2
COMMON="experiment=bandai_text dataset.datamodule.mirror=true dataset.datamodule.window_min_frames=40 trainer.check_val_every_n_epoch=100000 logger=csv checkpoint_every=500"
name=proxyB1
if [ ! -f outputs/train/$name/DONE ]; then
  ck=""; [ -f outputs/train/$name/checkpoints/last.ckpt ] && ck="ckpt_path=outputs/train/$name/checkpoints/last.ckpt"
  python train.py $COMMON trainer.max_steps=$STEPS "$@" condition.text_noise=0.3 hydra.run.dir=outputs/train/$name $ck > /tmp/$name.log 2>&1 && touch outputs/train/$name/DONE
fi
[ -f outputs/evaluate/val_proxyB1/metrics.json ] || python evaluate.py checkpoint=outputs/train/proxyB1/checkpoints/last.ckpt dataset=bandai split=val replications=2 mm_replications=0 guidance=2 wandb=false hydra.run.dir=outputs/evaluate/val_proxyB1 > /tmp/eval_proxyB1.log 2>&1
for n in $WIN proxyB1; do
  [ -f outputs/human_val/$n/paraphrases.json ] || python -m motiondiff.studies.action_accuracy checkpoint=outputs/train/$n/checkpoints/last.ckpt captions=data/paraphrases/bandai_human_val.json num_samples=5 guidance=2 sampler=ddim steps=50 out=outputs/human_val/$n > /tmp/human_$n.log 2>&1
done
