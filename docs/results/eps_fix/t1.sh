#!/bin/bash
# Run T1 of rules.md beside this file: the action eps cell of issue 43's ablation (as cell.sh eps_hml263 action runs
# it) with the geometric terms weighted per sample by abar_t, resumed from its run folder. Stop it with kill -9 <python
# pid> after the checkpoint that follows the in-training evaluation at step 2,000. Needs data/bandai (make data-full).
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
RUN=outputs/eps_fix/t1
train_sitting ablation_full $RUN "" $RUN.sittings.log ablation=eps_hml263 condition=action loss=geometric \
  loss.time_weighting=alpha_bar
