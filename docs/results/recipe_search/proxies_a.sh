#!/bin/bash
cd /work/main; source .venv/bin/activate
export LD_PRELOAD=/usr/lib/x86_64-linux-gnu/libtcmalloc_minimal.so.4
COMMON="experiment=bandai_text dataset.datamodule.mirror=true dataset.datamodule.window_min_frames=40 trainer.check_val_every_n_epoch=100000 logger=csv checkpoint_every=500"
run() { name=$1; steps=$2; shift 2
  if [ ! -f outputs/train/$name/DONE ]; then
    ck=""; [ -f outputs/train/$name/checkpoints/last.ckpt ] && ck="ckpt_path=outputs/train/$name/checkpoints/last.ckpt"
    python train.py $COMMON trainer.max_steps=$steps "$@" hydra.run.dir=outputs/train/$name $ck > /tmp/$name.log 2>&1 && touch outputs/train/$name/DONE
  fi
}
run proxyA1 6900
run proxyA2 3000 model.d_model=256 model.ff_size=512
for n in proxyA1 proxyA2; do
  [ -f outputs/evaluate/val_$n/metrics.json ] || python evaluate.py checkpoint=outputs/train/$n/checkpoints/last.ckpt dataset=bandai split=val replications=2 mm_replications=0 guidance=2 wandb=false hydra.run.dir=outputs/evaluate/val_$n > /tmp/eval_$n.log 2>&1
done
