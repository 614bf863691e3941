#!/bin/bash
# R1 of rules.md beside this file: the action x0 · hml263 ablation cell with the geometric losses summed per frame as
# MDM's equations 3-5 write them (loss.reduction=equation), stopped by run_all.sh after its step-2,000 checkpoint.
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/geometric_reduction/r1
ck=$(resume_arg $RUN "")
mkdir -p outputs/geometric_reduction
log_sitting $RUN.sittings.log "$ck"
python train.py experiment=ablation_full ablation=x0_hml263 condition=action loss=geometric loss.reduction=equation \
  hydra.run.dir=$RUN $ck
echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> $RUN.sittings.log
