#!/bin/bash
# Rule Y's fine-tunes of the shipped action model (rules.md beside this file), each resumed from its run folder when
# one exists, then measured on val: candidate.sh (the ship rule's numbers) and fid_gap.py (the gap by length). One
# torch thread (OMP_NUM_THREADS=1) beside other training. Needs data/bandai (make data-full).
#   OMP_NUM_THREADS=1 nohup docs/results/bandai_action/long_run/finetune_y.sh [y1:0.5] [y0:0] > outputs/finetune_y.log 2>&1 &
# Each argument is <name>:<first_window_share>; without arguments Y1, then Y0.
set -euo pipefail
cd "$(dirname "$0")/../../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
here=docs/results/bandai_action/long_run
[ $# -gt 0 ] || set -- y1:0.5 y0:0
for c in "$@"; do
  name=${c%%:*}; share=${c#*:}; run=outputs/train/bandai_action_$name
  if [ ! -f "$run/done" ]; then
    ck=$(resume_arg "$run"); log_sitting "$here/sittings_$name.log" "${ck:-init_from=checkpoints/models/bandai_action_trans_dec_14k.safetensors}"
    python train.py experiment=bandai_action_trans_dec \
      init_from=checkpoints/models/bandai_action_trans_dec_14k.safetensors optim.lr=1e-4 optim.warmup_steps=100 \
      trainer.max_steps=4000 dataset.datamodule.first_window_share="$share" logger=csv hydra.run.dir="$run" $ck
    echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> "$here/sittings_$name.log"; touch "$run/done"
  fi
  "$here/candidate.sh" "$run/checkpoints/last.ckpt" "$name"
  python docs/results/bandai_action/fid_gap/fid_gap.py "$run/checkpoints/last.ckpt" \
    > "docs/results/bandai_action/fid_gap/$name.md"
done
