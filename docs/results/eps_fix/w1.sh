#!/bin/bash
# W1 of rules.md beside this file (amendment 3): the action ε · hml263 cell with T1's training at width 272 (above the
# 263 features), stopped after its step-3,000 checkpoint. Needs data/bandai (make data-full).
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/eps_fix/w1
ck=$(resume_arg $RUN "")
mkdir -p outputs/eps_fix
log_sitting $RUN.sittings.log "$ck"
until_checkpoint $RUN/checkpoints/step0003000.ckpt outputs/eps_fix/w1.log \
  python train.py experiment=ablation_full ablation=eps_hml263 condition=action loss=geometric \
  loss.time_weighting=alpha_bar diffusion.timestep_spacing=leading model.d_model=272 model.ff_size=544 \
  hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends" >> $RUN.sittings.log
