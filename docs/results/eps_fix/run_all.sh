#!/bin/bash
# rules.md beside this file, end to end: T0 (the action ε cell, cell.sh) and T1 (t1.sh) each stopped after their
# step-2,000 checkpoint, then the six candidates S0-S5 measured on val (measure.sh). Resumable: a run whose
# step-2,000 checkpoint exists is not started again, and measure.sh's outputs are kept.
#   docs/results/eps_fix/run_all.sh
set -u
cd "$(dirname "$0")/../../.."
here=docs/results/eps_fix
t0=outputs/ablation_full/action_eps_hml263/checkpoints/step0002000.ckpt; t1=outputs/eps_fix/t1/checkpoints/step0002000.ckpt
source docs/results/sittings.sh  # until_checkpoint, cell_until_step
cell_until_step eps_hml263 action 0002000 "docs/results/eps_fix/rules.md: T0" || exit 1
until_checkpoint $t1 outputs/eps_fix_t1.log $here/t1.sh || exit 1
m() { [ -f $here/val/$2.json ] || $here/measure.sh "$@"; }
m $t0 S0 uniform none; m $t0 S1 leading none; m $t0 S2 uniform static; m $t0 S3 leading static
m $t1 S4 uniform none; m $t1 S5 leading none
echo done
