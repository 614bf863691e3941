#!/bin/bash
# R1 of rules.md beside this file: the action x0 · hml263 ablation cell with the geometric losses summed per frame as
# MDM's equations 3-5 write them (loss.reduction=equation), stopped by run_all.sh after its step-2,000 checkpoint.
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/geometric_reduction/r1
train_sitting ablation_full $RUN "" $RUN.sittings.log ablation=x0_hml263 condition=action loss=geometric \
  loss.reduction=equation
