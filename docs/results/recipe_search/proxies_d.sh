#!/bin/bash
# Round D (rules.md): A1's recipe with class-balanced clip drawing (balance 0.5), 6,900 steps, then its val numbers
# and the human-style val set, measured as round B measured A1. Resumes from its run folder.
cd "$(dirname "$0")/../../.."; source .venv/bin/activate
lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$lib" ] && export LD_PRELOAD=$lib
COMMON="experiment=bandai_text dataset.datamodule.mirror=true dataset.datamodule.window_min_frames=40 trainer.check_val_every_n_epoch=100000 logger=csv checkpoint_every=500"
name=proxyD1
if [ ! -f outputs/train/$name/DONE ]; then
  ck=""; [ -f outputs/train/$name/checkpoints/last.ckpt ] && ck="ckpt_path=outputs/train/$name/checkpoints/last.ckpt"
  python train.py $COMMON trainer.max_steps=6900 dataset.datamodule.balance=0.5 hydra.run.dir=outputs/train/$name $ck > /tmp/$name.log 2>&1 && touch outputs/train/$name/DONE
fi
[ -f outputs/evaluate/val_$name/metrics.json ] || python evaluate.py checkpoint=outputs/train/$name/checkpoints/last.ckpt dataset=bandai split=val replications=2 mm_replications=0 guidance=2 wandb=false hydra.run.dir=outputs/evaluate/val_$name > /tmp/eval_$name.log 2>&1
[ -f outputs/human_val/$name/paraphrases.json ] || python -m motiondiff.studies.action_accuracy checkpoint=outputs/train/$name/checkpoints/last.ckpt captions=data/paraphrases/bandai_human_val.json num_samples=5 guidance=2 sampler=ddim steps=50 out=outputs/human_val/$name > /tmp/human_$name.log 2>&1
